//! Scoring navigation runs (formats.md): which subgoals a trajectory's stops reached,
//! and the suite figures T_1..T_K and SR.
//!
//! Subgoal k is reached when a stop *after* the stop that reached subgoal k-1 lies
//! within [`SUCCESS_RADIUS_M`] of the object's footprint (polygon distance), inside
//! the region, or within [`SUCCESS_RADIUS_M`] of the point. Stops are matched in
//! order, each to the earliest qualifying stop, so one stop never counts for two
//! subgoals and the order of the instruction matters. When subgoal k is missed, the
//! search for subgoal k+1 goes on after the last stop that did reach one (so SR
//! credits later subgoals; T_k does not).

use map_core::{IvlMap, Point, Stop};
use planner_dsl::typed::Side;
use serde::{Deserialize, Serialize};

use super::suite::Subgoal;

/// Success threshold, metres (the paper's and VLMaps' 1.0 m).
pub const SUCCESS_RADIUS_M: f64 = 1.0;

/// Whether a robot standing at `p` satisfies `goal` on `map`. An object id or region
/// the map does not hold is never satisfied.
#[must_use]
pub fn satisfies(map: &IvlMap, goal: &Subgoal, p: Point) -> bool {
    match goal {
        Subgoal::Object(id) => map
            .instance_by_id(*id)
            .is_some_and(|i| i.distance(p) <= SUCCESS_RADIUS_M),
        Subgoal::Region(name) => map
            .regions
            .iter()
            .filter(|r| r.name == *name)
            .any(|r| r.polygon.contains(p)),
        Subgoal::Point(q) => p.dist(Point::new(q[0], q[1])) <= SUCCESS_RADIUS_M,
    }
}

/// Per subgoal, whether it was reached by the stops (in order, each stop at most once).
#[must_use]
pub fn reached(map: &IvlMap, subgoals: &[Subgoal], stops: &[Stop]) -> Vec<bool> {
    reaching_stops(map, subgoals, stops)
        .iter()
        .map(Option::is_some)
        .collect()
}

/// Per subgoal, the index in `stops` of the stop that reached it, as [`reached`]
/// matches them (`None`: missed).
#[must_use]
pub fn reaching_stops(map: &IvlMap, subgoals: &[Subgoal], stops: &[Stop]) -> Vec<Option<usize>> {
    let mut next = 0usize;
    subgoals
        .iter()
        .map(|g| {
            let hit = stops
                .iter()
                .enumerate()
                .skip(next)
                .find(|(_, s)| satisfies(map, g, Point::new(s.pose[0], s.pose[1])))
                .map(|(i, _)| i);
            if let Some(i) = hit {
                next = i + 1;
            }
            hit
        })
        .collect()
}

/// A subgoal that the task's reference plan reaches by a move to one side of the
/// object ("stop on the north side of the table": `move_north`), and the call of the
/// run's stop that reached it. The 1.0 m radius credits any stop beside the object, so
/// [`reached`] cannot tell whether the side was kept; this can.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct SideStop {
    /// The subgoal, counted from 1.
    pub subgoal: usize,
    /// The side function the reference plan stopped with, e.g. `move_north`.
    pub want: String,
    /// The library call of the run's stop that reached the subgoal; `None` when the
    /// run missed it.
    pub got: Option<String>,
}

impl SideStop {
    /// Whether the run reached the subgoal with the same side function.
    #[must_use]
    pub fn kept(&self) -> bool {
        self.got.as_deref() == Some(self.want.as_str())
    }
}

/// The subgoals whose reference stop (`reference`: the stops of the task's reference
/// plan) is a move to a side, with the call of the `run`'s stop that reached each.
#[must_use]
pub fn side_stops(
    map: &IvlMap,
    subgoals: &[Subgoal],
    reference: &[Stop],
    run: &[Stop],
) -> Vec<SideStop> {
    let want = reaching_stops(map, subgoals, reference);
    let got = reaching_stops(map, subgoals, run);
    want.iter()
        .zip(&got)
        .enumerate()
        .filter_map(|(k, (w, g))| {
            let call = &reference.get((*w)?)?.call;
            Side::from_function(call).filter(|s| s.is_move())?;
            Some(SideStop {
                subgoal: k + 1,
                want: call.clone(),
                got: g.and_then(|i| run.get(i)).map(|s| s.call.clone()),
            })
        })
        .collect()
}

/// Suite-level navigation figures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NavScores {
    /// `T[k-1]` = share of tasks (among those with at least k subgoals) whose first k
    /// subgoals were all reached.
    #[serde(rename = "T")]
    pub t: Vec<f64>,
    /// Share of all subgoals reached.
    #[serde(rename = "SR")]
    pub sr: f64,
}

/// T_1..T_K (K = the most subgoals of any task) and SR over per-task `reached` lists.
#[must_use]
pub fn nav_scores(per_task: &[Vec<bool>]) -> NavScores {
    let k_max = per_task.iter().map(Vec::len).max().unwrap_or(0);
    let t = (1..=k_max)
        .map(|k| {
            let eligible: Vec<&Vec<bool>> = per_task.iter().filter(|r| r.len() >= k).collect();
            let ok = eligible
                .iter()
                .filter(|r| r[..k].iter().all(|b| *b))
                .count();
            ratio(ok, eligible.len())
        })
        .collect();
    let total: usize = per_task.iter().map(Vec::len).sum();
    let hit: usize = per_task
        .iter()
        .map(|r| r.iter().filter(|b| **b).count())
        .sum();
    NavScores {
        t,
        sr: ratio(hit, total),
    }
}

pub(crate) fn ratio(a: usize, b: usize) -> f64 {
    if b == 0 {
        0.0
    } else {
        a as f64 / b as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use map_core::{Scene, StopTarget};

    /// Table 1 at (2, 2) 1x1 m, table 2 at (8, 2); kitchen is x in [5, 10].
    fn map() -> IvlMap {
        let s = Scene::from_json_str(
            r#"{"format": "ivlmap-scene/1", "name": "s", "bounds": [0, 0, 10, 4],
            "regions": [{"name": "kitchen", "polygon": [[5,0],[10,0],[10,4],[5,4]]}],
            "objects": [{"id": 1, "category": "table", "colour": "red", "center": [2, 2], "size": [1, 1]},
                        {"id": 2, "category": "table", "colour": "blue", "center": [8, 2], "size": [1, 1]}],
            "robot": {"pose": [0.5, 0.5, 0], "radius": 0.2}}"#,
            "s.scene.json",
        )
        .unwrap();
        IvlMap::from_scene(&s)
    }

    fn stop(x: f64, y: f64) -> Stop {
        Stop {
            pose: [x, y, 0.0],
            call: "move_to".into(),
            target: StopTarget::Point([x, y]),
            goal: None,
            snapped: false,
        }
    }

    #[test]
    fn distance_is_to_the_footprint_not_the_centre() {
        let m = map();
        // 0.95 m from the table's east edge (x = 2.5), 1.45 m from its centre.
        assert!(satisfies(&m, &Subgoal::Object(1), Point::new(3.45, 2.0)));
        assert!(!satisfies(&m, &Subgoal::Object(1), Point::new(3.55, 2.0)));
        // Diagonal: corner (2.5, 2.5), point 0.8/0.8 away -> 1.13 m.
        assert!(!satisfies(&m, &Subgoal::Object(1), Point::new(3.3, 3.3)));
        assert!(satisfies(
            &m,
            &Subgoal::Region("kitchen".into()),
            Point::new(6.0, 1.0)
        ));
        assert!(!satisfies(
            &m,
            &Subgoal::Region("kitchen".into()),
            Point::new(4.9, 1.0)
        ));
        assert!(!satisfies(
            &m,
            &Subgoal::Region("attic".into()),
            Point::new(6.0, 1.0)
        ));
        assert!(satisfies(
            &m,
            &Subgoal::Point([1.0, 1.0]),
            Point::new(1.6, 1.6)
        ));
        assert!(!satisfies(&m, &Subgoal::Object(99), Point::new(2.0, 2.0)));
    }

    #[test]
    fn order_matters_and_a_stop_counts_once() {
        let m = map();
        let goals = [Subgoal::Object(1), Subgoal::Object(2)];
        // Right order.
        assert_eq!(
            reached(&m, &goals, &[stop(3.0, 2.0), stop(7.0, 2.0)]),
            vec![true, true]
        );
        // Wrong order: table 2 first, then table 1; table 2 is never visited after table 1.
        assert_eq!(
            reached(&m, &goals, &[stop(7.0, 2.0), stop(3.0, 2.0)]),
            vec![true, false]
        );
        // One stop cannot serve two subgoals, even when it satisfies both.
        let both = [Subgoal::Object(2), Subgoal::Region("kitchen".into())];
        assert_eq!(reached(&m, &both, &[stop(7.0, 2.0)]), vec![true, false]);
        assert_eq!(
            reached(&m, &both, &[stop(7.0, 2.0), stop(6.0, 1.0)]),
            vec![true, true]
        );
        // The same object twice needs two stops.
        let twice = [Subgoal::Object(1), Subgoal::Object(1)];
        assert_eq!(reached(&m, &twice, &[stop(3.0, 2.0)]), vec![true, false]);
        // A miss in the middle: later subgoals still count for SR.
        let three = [
            Subgoal::Object(1),
            Subgoal::Point([0.5, 3.5]),
            Subgoal::Object(2),
        ];
        assert_eq!(
            reached(&m, &three, &[stop(3.0, 2.0), stop(7.0, 2.0)]),
            vec![true, false, true]
        );
        assert_eq!(reached(&m, &three, &[]), vec![false, false, false]);
        assert_eq!(
            reaching_stops(&m, &three, &[stop(3.0, 2.0), stop(7.0, 2.0)]),
            vec![Some(0), None, Some(1)]
        );
    }

    #[test]
    fn a_side_stop_is_kept_only_by_the_same_side_function() {
        let m = map();
        let goals = [
            Subgoal::Object(1),
            Subgoal::Object(2),
            Subgoal::Region("kitchen".into()),
        ];
        let at = |x: f64, call: &str| Stop {
            call: call.into(),
            ..stop(x, 2.0)
        };
        // The reference stops north of table 1 (a side), at table 2 and in the kitchen.
        let reference = [
            at(2.0, "move_north"),
            at(7.0, "move_to_object"),
            at(6.0, "move_to_object"),
        ];
        let sides = |run: &[Stop]| side_stops(&m, &goals, &reference, run);
        let want = |got: Option<&str>| {
            vec![SideStop {
                subgoal: 1,
                want: "move_north".into(),
                got: got.map(Into::into),
            }]
        };
        let same = sides(&reference);
        assert_eq!(same, want(Some("move_north")));
        assert!(same[0].kept());
        // Reached within 1.0 m by the plain move: reached, but the side was not kept.
        let plain = sides(&[at(3.0, "move_to_object"), at(7.0, "move_to_object")]);
        assert_eq!(plain, want(Some("move_to_object")));
        assert!(!plain[0].kept());
        assert!(!sides(&[at(3.0, "move_south")])[0].kept(), "another side");
        assert_eq!(sides(&[]), want(None));
        // A turn putting the object on one side is not a side stop.
        let turn = [at(2.0, "with_object_on_left"), at(7.0, "move_to_object")];
        assert!(side_stops(&m, &goals, &turn, &turn).is_empty());
    }

    #[test]
    fn t_k_and_sr() {
        let s = nav_scores(&[
            vec![true, true, true, true],
            vec![true, false, true, true],
            vec![false, true, true, true],
            vec![true, true, true, false],
        ]);
        assert_eq!(s.t, vec![0.75, 0.5, 0.5, 0.25]);
        assert!((s.sr - 13.0 / 16.0).abs() < 1e-12);
        let e = nav_scores(&[]);
        assert!(e.t.is_empty() && e.sr == 0.0);
        // Tasks with fewer subgoals count only for the T_k they have.
        let s = nav_scores(&[vec![true], vec![true, false]]);
        assert_eq!(s.t, vec![1.0, 0.0]);
    }
}
