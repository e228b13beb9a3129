//! Selections: everything a noun phrase says about which instance it means, as one
//! value ("the second red chair next to the table in the kitchen"), and the one place
//! that resolves it against the instance table.
//!
//! The semantics are design.md's "What people say, and what it means":
//!
//! | people say | selection |
//! |---|---|
//! | "the 3rd chair", "chair number 3", "table three" | `ordinal: 3` |
//! | "the last chair", "the farthest chair", "the chair furthest from you" | `ordinal: -1` (near_to_far) |
//! | "the second to last chair", "the penultimate chair" | `ordinal: 2`, the reversed order (`far_to_near`), or `ordinal: -2` (n-th from the end) |
//! | "the red sofa", "the sofa, the red one", "a red sofa" | `colour: "red"` |
//! | "the table that isn't yellow" | `not_colour: "yellow"` |
//! | "the other red chair" (after visiting red chair 9), "a different one" | `other_than: 9` |
//! | "the bench you visited first", "the first bike you went to" | `visited: 1` (counted in the order of first visits) |
//! | "that same chair again", "the chair you were just at" | `visited: -1` (the latest visited) |
//! | "the lamp you haven't been to yet" | `not_visited: true` (then the nearest of the rest) |
//! | "the plant in the lounge" | `region: "lounge"` |
//! | "the biggest table", "the smallest plant" | `ordinal: 1`, `largest_to_smallest` / `smallest_to_largest` |
//! | "the chair next to / nearest / by the table" | `near: <the table's id>` (distances from its footprint) |
//! | "between the two yellow tables" | [`IvlMap::select_pair`]: exactly two must match |
//!
//! Filters apply first (name, region, colour, excluded colour, the anchor itself
//! left out, the instance `other_than` names left out, with `not_visited` every visited
//! instance left out), then the order ranks what is left and the ordinal picks. With
//! `visited: k` only the visited instances stay, ranked in the order they were visited
//! (first visits for k >= 1, latest visits for k <= -1), and k picks; `visited` and
//! `ordinal` together are an error, never one silently winning. The visits are the
//! caller's (the conversation's visited instances, oldest first:
//! [`IvlMap::select_visited`]); [`IvlMap::select`] has none.
//!
//! ```
//! use map_core::select::Selection;
//! use map_core::{IvlMap, Pose, Scene};
//! let scene = Scene::from_json_str(
//!     r#"{"format": "ivlmap-scene/1", "name": "t", "bounds": [0, 0, 10, 4],
//!         "objects": [
//!           {"id": 1, "category": "table", "colour": "yellow", "center": [2, 2], "size": [1, 1]},
//!           {"id": 2, "category": "chair", "colour": "red", "center": [3.2, 2], "size": [0.5, 0.5]},
//!           {"id": 3, "category": "chair", "colour": "red", "center": [8, 2], "size": [0.5, 0.5]},
//!           {"id": 4, "category": "table", "colour": "black", "center": [9, 2], "size": [1.5, 1]}],
//!         "robot": {"pose": [0.5, 0.5, 0], "radius": 0.2}}"#,
//!     "t.scene.json",
//! )
//! .unwrap();
//! let map = IvlMap::from_scene(&scene);
//! let robot = map.start_pose;
//! // "the chair next to the black table": chair 3, although chair 2 is nearer the robot
//! let near = Selection::new("chair").near(4);
//! assert_eq!(map.select(&near, robot).unwrap().id, 3);
//! // "the table that isn't yellow"
//! assert_eq!(map.select(&Selection::new("table").not_colour("yellow"), robot).unwrap().id, 4);
//! // "the biggest table"
//! let big = Selection::new("table").ordered("largest_to_smallest").unwrap();
//! assert_eq!(map.select(&big, robot).unwrap().id, 4);
//! // "now the other red chair", after red chair 2
//! let other = Selection::new("chair").colour("red").other_than(2);
//! assert_eq!(map.select(&other, robot).unwrap().id, 3);
//! ```

use serde::{Deserialize, Serialize};

use crate::geometry::Pose;
use crate::goals::closest_points;
use crate::map::{Instance, IvlMap};
use crate::matcher::{canonical, is_colour_word, plural, LexicalMatcher, NameMatcher};
use crate::query::{ObjectOrder, QueryError};

/// Which instance a noun phrase means: a category name, filters, an order and an
/// ordinal. Built with [`Selection::new`] and the builder methods; resolved by
/// [`IvlMap::select`].
///
/// `A` is how the anchor of "next to" is held: an instance id here (resolved); the plan
/// language's typed plan holds the object expression instead
/// (`planner_dsl::typed::Target`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Selection<A = u32> {
    /// The category as said ("couch" finds the sofas through the matcher).
    pub name: String,
    /// k >= 1 the k-th in the order, -1 the last, 0 the first (unspecified).
    #[serde(default)]
    pub ordinal: i64,
    /// Only instances of this colour.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub colour: Option<String>,
    /// Only instances not of this colour ("the table that isn't yellow").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub not_colour: Option<String>,
    /// The order the ordinal counts in.
    #[serde(default)]
    pub order: ObjectOrder,
    /// Only instances whose footprint centroid lies in this region.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<String>,
    /// An anchor instance id: distances (near_to_far, far_to_near) are measured from its
    /// footprint instead of from the robot, and the anchor itself is left out.
    #[serde(default = "Option::default", skip_serializing_if = "Option::is_none")]
    pub near: Option<A>,
    /// An instance left out ("the other red chair", said after visiting one): the
    /// same kind as the selection's name, or the selection is an error
    /// ([`QueryError::OtherThanElsewhere`]); the ordinal counts what is left.
    #[serde(default = "Option::default", skip_serializing_if = "Option::is_none")]
    pub other_than: Option<A>,
    /// Counted among the instances visited so far, in the order visited: k >= 1 the
    /// k-th visited ("the bench you visited first"), -1 the latest visited ("that same
    /// chair again"), 0 not given.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub visited: i64,
    /// Only instances not visited so far ("the lamp you haven't been to yet").
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub not_visited: bool,
}

#[allow(clippy::trivially_copy_pass_by_ref)] // serde's skip_serializing_if passes a reference
fn is_zero(k: &i64) -> bool {
    *k == 0
}

impl<A> Default for Selection<A> {
    fn default() -> Self {
        Selection {
            name: String::new(),
            ordinal: 0,
            colour: None,
            not_colour: None,
            order: ObjectOrder::default(),
            region: None,
            near: None,
            other_than: None,
            visited: 0,
            not_visited: false,
        }
    }
}

impl<A> Selection<A> {
    /// Any instance called `name`; the first in the default order (the nearest).
    #[must_use]
    pub fn new(name: impl Into<String>) -> Self {
        Selection {
            name: name.into(),
            ..Selection::default()
        }
    }

    /// The k-th (k >= 1), the last (-1) or the first (0).
    #[must_use]
    pub fn nth(mut self, k: i64) -> Self {
        self.ordinal = k;
        self
    }

    /// Only instances of `colour`.
    #[must_use]
    pub fn colour(mut self, colour: impl Into<String>) -> Self {
        self.colour = Some(colour.into());
        self
    }

    /// Only instances not of `colour`.
    #[must_use]
    pub fn not_colour(mut self, colour: impl Into<String>) -> Self {
        self.not_colour = Some(colour.into());
        self
    }

    /// Counting in `order` (an order name, see [`ObjectOrder::parse`]).
    ///
    /// # Errors
    /// [`QueryError::UnknownOrder`] for a name that is no order.
    pub fn ordered(mut self, order: &str) -> Result<Self, QueryError> {
        self.order = ObjectOrder::parse(order)?;
        Ok(self)
    }

    /// Only instances in the region `region`.
    #[must_use]
    pub fn in_region(mut self, region: impl Into<String>) -> Self {
        self.region = Some(region.into());
        self
    }

    /// Ranked by distance from the footprint of `anchor`.
    #[must_use]
    pub fn near(mut self, anchor: A) -> Self {
        self.near = Some(anchor);
        self
    }

    /// Leaving out `instance` ("the other one").
    #[must_use]
    pub fn other_than(mut self, instance: A) -> Self {
        self.other_than = Some(instance);
        self
    }

    /// The k-th visited (k >= 1, in the order of first visits) or the latest visited
    /// (-1, in the order of latest visits), among the instances visited so far.
    #[must_use]
    pub fn visited(mut self, k: i64) -> Self {
        self.visited = k;
        self
    }

    /// Leaving out every instance visited so far.
    #[must_use]
    pub fn not_visited(mut self) -> Self {
        self.not_visited = true;
        self
    }
}

/// The distance between two footprints (0 when they touch).
fn footprint_distance(a: &Instance, b: &Instance) -> f64 {
    closest_points(&a.contour, &b.contour).map_or(f64::INFINITY, |(p, q)| p.dist(q))
}

/// `noun` with the selection's colour in front ("yellow tables"), for messages.
fn coloured<A>(noun: String, sel: &Selection<A>) -> String {
    match given(sel.colour.as_deref()) {
        Some(c) => format!("{c} {noun}"),
        None => noun,
    }
}

/// Trimmed, and `None` when empty.
fn given(s: Option<&str>) -> Option<&str> {
    s.map(str::trim).filter(|c| !c.is_empty())
}

impl IvlMap {
    /// The instance `sel` means, with the built-in lexical matcher.
    ///
    /// # Errors
    /// A [`QueryError`] that says what the map holds: no such name, region or colour,
    /// every candidate excluded, an ordinal past the count, an unknown anchor.
    pub fn select(&self, sel: &Selection, robot: Pose) -> Result<&Instance, QueryError> {
        self.select_with(&LexicalMatcher, sel, robot)
    }

    /// [`IvlMap::select`] after `visits`: the instances visited so far, oldest first (a
    /// repeat visit listed again), which `visited` and `not_visited` count over.
    ///
    /// # Errors
    /// As [`IvlMap::select`]; and [`QueryError::NoneVisited`],
    /// [`QueryError::AllVisited`] or [`QueryError::TwoCounts`] for the visit keys.
    pub fn select_visited(
        &self,
        sel: &Selection,
        robot: Pose,
        visits: &[u32],
    ) -> Result<&Instance, QueryError> {
        self.pick_after(&LexicalMatcher, sel, robot, visits)
    }

    /// [`IvlMap::select`] with a chosen [`NameMatcher`].
    ///
    /// # Errors
    /// As [`IvlMap::select`].
    pub fn select_with(
        &self,
        matcher: &dyn NameMatcher,
        sel: &Selection,
        robot: Pose,
    ) -> Result<&Instance, QueryError> {
        self.pick_after(matcher, sel, robot, &[])
    }

    fn pick_after(
        &self,
        matcher: &dyn NameMatcher,
        sel: &Selection,
        robot: Pose,
        visits: &[u32],
    ) -> Result<&Instance, QueryError> {
        let k = if sel.visited == 0 {
            sel.ordinal
        } else {
            sel.visited
        };
        let (label, cands) = self.candidates_visited(matcher, sel, robot, visits)?;
        // k >= 1 counts from the front, -n from the back (-1 the last, -2 the second to
        // last), 0 is the first (the nearest by default).
        let idx = match k {
            0 => 0,
            k if k > 0 => usize::try_from(k - 1).unwrap_or(usize::MAX),
            k => usize::try_from(k.unsigned_abs())
                .ok()
                .and_then(|n| cands.len().checked_sub(n))
                .unwrap_or(usize::MAX),
        };
        cands.get(idx).copied().ok_or_else(|| {
            let noun = if cands.len() == 1 {
                label.clone()
            } else {
                plural(&label)
            };
            QueryError::OrdinalPastCount {
                what: coloured(noun, sel),
                count: cands.len(),
                k,
            }
        })
    }

    /// "Between the two yellow tables": the two instances `sel`'s filters leave, in
    /// its order; an error naming how many match when that is not exactly two.
    ///
    /// # Errors
    /// [`QueryError::NotExactlyTwo`] with the count, or the errors of
    /// [`IvlMap::select`] when nothing matches at all.
    pub fn select_pair(&self, sel: &Selection, robot: Pose) -> Result<[&Instance; 2], QueryError> {
        self.select_pair_visited(sel, robot, &[])
    }

    /// [`IvlMap::select_pair`] after `visits` (as [`IvlMap::select_visited`]).
    ///
    /// # Errors
    /// As [`IvlMap::select_pair`] and [`IvlMap::select_visited`].
    pub fn select_pair_visited(
        &self,
        sel: &Selection,
        robot: Pose,
        visits: &[u32],
    ) -> Result<[&Instance; 2], QueryError> {
        let (label, cands) = self.candidates_visited(&LexicalMatcher, sel, robot, visits)?;
        match cands[..] {
            [a, b] => Ok([a, b]),
            _ => Err(QueryError::NotExactlyTwo {
                what: coloured(plural(&label), sel),
                count: cands.len(),
                ids: cands.iter().map(|i| i.id).collect(),
            }),
        }
    }

    /// The instances `sel`'s filters leave (never empty), ranked in its order, with
    /// the matched label.
    ///
    /// # Errors
    /// As [`IvlMap::select`], but for the ordinal.
    pub fn candidates_with(
        &self,
        matcher: &dyn NameMatcher,
        sel: &Selection,
        robot: Pose,
    ) -> Result<(String, Vec<&Instance>), QueryError> {
        self.candidates_visited(matcher, sel, robot, &[])
    }

    /// [`IvlMap::candidates_with`] after `visits` (as [`IvlMap::select_visited`]); with
    /// `visited` given, the visited candidates in the order of their visits.
    ///
    /// # Errors
    /// As [`IvlMap::select_visited`], but for the ordinal.
    pub fn candidates_visited(
        &self,
        matcher: &dyn NameMatcher,
        sel: &Selection,
        robot: Pose,
        visits: &[u32],
    ) -> Result<(String, Vec<&Instance>), QueryError> {
        if sel.visited != 0 && (sel.ordinal != 0 || sel.not_visited) {
            return Err(QueryError::TwoCounts {
                other: if sel.not_visited {
                    "not_visited"
                } else {
                    "ordinal"
                },
            });
        }
        let labels: Vec<&str> = {
            let mut v: Vec<&str> = self.instances.iter().map(|i| i.label.as_str()).collect();
            v.sort_unstable();
            v.dedup();
            v
        };
        let label = matcher
            .best(&sel.name, &labels)
            .ok_or_else(|| QueryError::UnknownObject {
                name: sel.name.trim().to_string(),
                known: self.label_counts(),
            })?
            .to_string();
        let anchor = match sel.near {
            Some(id) => Some(
                self.instance_by_id(id)
                    .ok_or(QueryError::UnknownInstance { id })?,
            ),
            None => None,
        };
        if let Some(id) = sel.other_than {
            let left_out = self
                .instance_by_id(id)
                .ok_or(QueryError::UnknownInstance { id })?;
            if left_out.label != label {
                return Err(QueryError::OtherThanElsewhere {
                    id,
                    its: left_out.label.clone(),
                    name: label,
                });
            }
        }
        let mut same: Vec<&Instance> = self
            .instances
            .iter()
            .filter(|i| i.label == label && Some(i.id) != sel.near)
            .collect();
        if same.is_empty() {
            // the anchor was the only one: "the table next to the table" with one table
            return Err(QueryError::OrdinalPastCount {
                what: format!("other {}", plural(&label)),
                count: 0,
                k: sel.ordinal.max(1),
            });
        }
        let mut region = None;
        if let Some(name) = given(sel.region.as_deref()) {
            let r = self.find_region_with(matcher, name)?;
            region = Some(r.name.clone());
            let all = same.len();
            same.retain(|i| r.polygon.contains(i.centroid));
            if same.is_empty() {
                return Err(QueryError::NoneInRegion {
                    name: label,
                    region: r.name.clone(),
                    elsewhere: all,
                });
            }
        }
        for c in [
            given(sel.colour.as_deref()),
            given(sel.not_colour.as_deref()),
        ]
        .into_iter()
        .flatten()
        {
            if !is_colour_word(c) && !self.colours.iter().any(|m| canonical(m) == canonical(c)) {
                return Err(QueryError::NotAColour {
                    name: label,
                    colour: c.to_string(),
                    known: self.colours.clone(),
                });
            }
        }
        let is = |i: &Instance, c: &str| {
            i.colour
                .as_deref()
                .is_some_and(|ic| canonical(ic) == canonical(c))
        };
        let mut cands: Vec<&Instance> = same
            .iter()
            .copied()
            .filter(|i| given(sel.colour.as_deref()).is_none_or(|c| is(i, c)))
            .filter(|i| given(sel.not_colour.as_deref()).is_none_or(|c| !is(i, c)))
            .collect();
        if cands.is_empty() {
            if let Some(c) = given(sel.not_colour.as_deref()) {
                if given(sel.colour.as_deref()).is_none() {
                    return Err(QueryError::AllExcluded {
                        name: label,
                        colour: c.to_string(),
                    });
                }
            }
            let mut available: Vec<(Option<String>, usize)> = Vec::new();
            for i in &same {
                match available.iter_mut().find(|(col, _)| *col == i.colour) {
                    Some((_, n)) => *n += 1,
                    None => available.push((i.colour.clone(), 1)),
                }
            }
            available.sort_by(|a, b| (a.0.is_none(), &a.0).cmp(&(b.0.is_none(), &b.0)));
            return Err(QueryError::NoSuchColour {
                name: label,
                colour: given(sel.colour.as_deref()).unwrap_or_default().to_string(),
                available,
                region,
            });
        }
        if let Some(id) = sel.other_than {
            cands.retain(|i| i.id != id);
            if cands.is_empty() {
                // "the other red chair" where the one visited is the only red chair
                return Err(QueryError::OrdinalPastCount {
                    what: format!("other {}", coloured(plural(&label), sel)),
                    count: 0,
                    k: sel.ordinal.max(1),
                });
            }
        }
        if sel.not_visited {
            cands.retain(|i| !visits.contains(&i.id));
            if cands.is_empty() {
                return Err(QueryError::AllVisited {
                    what: coloured(label, sel),
                });
            }
        }
        if sel.visited != 0 {
            cands.retain(|i| visits.contains(&i.id));
            if cands.is_empty() {
                return Err(QueryError::NoneVisited {
                    what: coloured(label, sel),
                });
            }
            // First visits count from the front, latest visits from the back: after
            // chair 2, chair 5, chair 2 again, the first visited is 2 and so is the latest.
            let at = |i: &Instance| {
                if sel.visited > 0 {
                    visits.iter().position(|v| *v == i.id)
                } else {
                    visits.iter().rposition(|v| *v == i.id)
                }
            };
            cands.sort_by_key(|i| at(i));
            return Ok((label, cands));
        }
        let key = |i: &Instance| match (anchor, sel.order) {
            (Some(a), ObjectOrder::NearToFar) => footprint_distance(a, i),
            (Some(a), ObjectOrder::FarToNear) => -footprint_distance(a, i),
            _ => sel.order.key(i, robot),
        };
        cands.sort_by(|a, b| key(a).total_cmp(&key(b)).then(a.id.cmp(&b.id)));
        Ok((label, cands))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point;
    use crate::scene::Scene;

    /// Robot at the origin facing north. Four tables along y = 3 (yellow 1 x 1 at
    /// x = 1, black at 2.5, yellow at 4, grey 2 x 1 at 7), a red chair beside each of
    /// tables 1 and 4 (north of them), a blue one beside table 3, a kitchen around the
    /// east half.
    fn map() -> IvlMap {
        let s = Scene::from_json_str(
            r#"{"format": "ivlmap-scene/1", "name": "s", "bounds": [-1, -1, 10, 7], "cell_size": 0.05,
            "regions": [{"name": "kitchen", "polygon": [[5,-1],[10,-1],[10,7],[5,7]]}],
            "objects": [
              {"id": 1, "category": "table", "colour": "yellow", "center": [1.0, 3.0], "size": [1.0, 1.0]},
              {"id": 2, "category": "table", "colour": "black", "center": [2.5, 3.0], "size": [0.8, 0.8]},
              {"id": 3, "category": "table", "colour": "yellow", "center": [4.0, 3.0], "size": [0.8, 0.8]},
              {"id": 4, "category": "table", "colour": "grey", "center": [7.0, 3.0], "size": [2.0, 1.0]},
              {"id": 11, "category": "chair", "colour": "red", "center": [1.0, 4.2], "size": [0.5, 0.5]},
              {"id": 13, "category": "chair", "colour": "blue", "center": [4.0, 4.1], "size": [0.5, 0.5]},
              {"id": 14, "category": "chair", "colour": "red", "center": [7.0, 4.3], "size": [0.5, 0.5]}
            ],
            "robot": {"pose": [0, 0, 0], "radius": 0.2}}"#,
            "s.scene.json",
        )
        .unwrap();
        IvlMap::from_scene(&s)
    }

    fn map_with_one_table() -> IvlMap {
        let s = Scene::from_json_str(
            r#"{"format": "ivlmap-scene/1", "name": "one", "bounds": [0, 0, 4, 4],
            "objects": [{"id": 1, "category": "table", "colour": "red", "center": [2, 2], "size": [1, 1]}],
            "robot": {"pose": [0.5, 0.5, 0], "radius": 0.2}}"#,
            "one.scene.json",
        )
        .unwrap();
        IvlMap::from_scene(&s)
    }

    const ORIGIN: Pose = Pose {
        position: Point::new(0.0, 0.0),
        heading: 0.0,
    };

    fn pick(m: &IvlMap, s: &Selection) -> u32 {
        m.select(s, ORIGIN).unwrap().id
    }

    #[test]
    fn the_farthest_is_the_last_nearest_first() {
        let m = map();
        assert_eq!(pick(&m, &Selection::new("table").nth(-1)), 4);
        assert_eq!(pick(&m, &Selection::new("table")), 1);
    }

    #[test]
    fn second_to_last_counts_the_reversed_order() {
        let m = map();
        // penultimate by distance: the 2nd farthest
        let far = Selection::new("table")
            .ordered("far_to_near")
            .unwrap()
            .nth(2);
        assert_eq!(pick(&m, &far), 3);
        // second to last from the west = 2nd from the east
        let west = Selection::new("table").ordered("west_to_east").unwrap();
        let mut east = west.clone().nth(2);
        east.order = west.order.reversed();
        assert_eq!(pick(&m, &east), 3);
        assert_eq!(ObjectOrder::EastToWest.reversed(), ObjectOrder::WestToEast);
        // -n counts from the end of the order itself: -2 is the same instance.
        assert_eq!(pick(&m, &Selection::new("table").nth(-2)), 3);
        assert_eq!(pick(&m, &west.clone().nth(-2)), 3);
        let past = m
            .select(&Selection::new("table").nth(-9), ORIGIN)
            .unwrap_err();
        assert!(
            past.to_string().ends_with("asked for the 9th to last"),
            "{past}"
        );
        for (o, _) in ObjectOrder::ALL {
            assert_eq!(o.reversed().reversed(), o);
            assert_ne!(o.reversed(), o);
        }
    }

    #[test]
    fn a_number_is_the_kth_and_past_the_count_says_how_many() {
        let m = map();
        assert_eq!(pick(&m, &Selection::new("chair").nth(3)), 14);
        let e = m
            .select(&Selection::new("chair").nth(4), ORIGIN)
            .unwrap_err();
        assert_eq!(e.to_string(), "there are 3 chairs; asked for the 4th");
    }

    #[test]
    fn next_to_ranks_by_footprint_distance_from_the_anchor() {
        let m = map();
        // "the chair next to the grey table": chair 14, though 11 is nearer the robot
        assert_eq!(pick(&m, &Selection::new("chair").near(4)), 14);
        // "the second chair closest to table 3": chair 13 first, then whichever of 11
        // and 14 has the nearer footprint
        let d = |a: u32, b: u32| {
            let (a, b) = (m.instance_by_id(a).unwrap(), m.instance_by_id(b).unwrap());
            footprint_distance(a, b)
        };
        let second = if d(3, 11) < d(3, 14) { 11 } else { 14 };
        assert_eq!(pick(&m, &Selection::new("chair").near(3)), 13);
        assert_eq!(pick(&m, &Selection::new("chair").near(3).nth(2)), second);
        // the colour filter first: the red chair next to table 3
        assert_eq!(
            pick(&m, &Selection::new("chair").colour("red").near(3)),
            second
        );
        // the anchor itself is never the answer: "the table next to table 2"
        let t = pick(&m, &Selection::new("table").near(2));
        assert!(t == 1 || t == 3, "{t}");
        assert!(matches!(
            m.select(&Selection::new("chair").near(99), ORIGIN),
            Err(QueryError::UnknownInstance { id: 99 })
        ));
        // "the table next to the table" where there is one table: an error, not a panic
        let lone = map_with_one_table();
        let e = lone
            .select(&Selection::new("table").near(1), ORIGIN)
            .unwrap_err();
        assert_eq!(e.to_string(), "there are 0 other tables; asked for the 1st");
    }

    #[test]
    fn visited_counts_in_the_order_of_visits() {
        let m = map();
        // tables visited 3, then 1, then 3 again; chair 14 between
        let visits = [3, 14, 1, 3];
        let sel = |s: Selection| m.select_visited(&s, ORIGIN, &visits).map(|i| i.id);
        // "the table you visited first": 3, although 1 is nearer
        assert_eq!(sel(Selection::new("table").visited(1)), Ok(3));
        assert_eq!(sel(Selection::new("table").visited(2)), Ok(1));
        // "that same table again": the latest visit, 3 (visited after 1)
        assert_eq!(sel(Selection::new("table").visited(-1)), Ok(3));
        assert_eq!(sel(Selection::new("table").visited(-2)), Ok(1));
        // filters first: "the yellow table you visited first" with a colour
        assert_eq!(
            sel(Selection::new("table").colour("yellow").visited(2)),
            Ok(1)
        );
        assert_eq!(sel(Selection::new("chair").visited(-1)), Ok(14));
        // past the count, and nothing visited of the kind: errors that say so
        let e = m
            .select_visited(&Selection::new("table").visited(3), ORIGIN, &visits)
            .unwrap_err();
        assert_eq!(e.to_string(), "there are 2 tables; asked for the 3rd");
        let e = m
            .select_visited(
                &Selection::new("table").colour("black").visited(1),
                ORIGIN,
                &visits,
            )
            .unwrap_err();
        assert_eq!(e.to_string(), "no black table has been visited yet");
        // without visits (a plain select) nothing has been visited
        let e = m
            .select(&Selection::new("table").visited(1), ORIGIN)
            .unwrap_err();
        assert!(matches!(e, QueryError::NoneVisited { .. }), "{e}");
    }

    #[test]
    fn not_visited_leaves_every_visited_one_out() {
        let m = map();
        let visits = [1, 11];
        let sel = |s: Selection| m.select_visited(&s, ORIGIN, &visits).map(|i| i.id);
        // "a table you haven't been to yet": the nearest of 2, 3, 4
        assert_eq!(sel(Selection::new("table").not_visited()), Ok(2));
        assert_eq!(sel(Selection::new("table").not_visited().nth(-1)), Ok(4));
        // "the red chair you haven't been to": 14, the one red chair left
        assert_eq!(
            sel(Selection::new("chair").colour("red").not_visited()),
            Ok(14)
        );
        let e = m
            .select_visited(
                &Selection::new("chair").colour("red").not_visited(),
                ORIGIN,
                &[11, 14],
            )
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "every red chair here has been visited already"
        );
    }

    #[test]
    fn visited_with_another_count_is_an_error_not_a_choice() {
        let m = map();
        for s in [
            Selection::new("table").visited(1).nth(2),
            Selection::new("table").visited(-1).not_visited(),
        ] {
            let e = m.select_visited(&s, ORIGIN, &[1, 3]).unwrap_err();
            assert!(matches!(e, QueryError::TwoCounts { .. }), "{e}");
        }
        // and a pair after visits leaves the visited out the same way
        let pair = m
            .select_pair_visited(&Selection::new("table").not_visited(), ORIGIN, &[1, 2])
            .unwrap();
        assert_eq!([pair[0].id, pair[1].id], [3, 4]);
    }

    #[test]
    fn in_a_region_only_counts_what_is_inside() {
        let m = map();
        assert_eq!(pick(&m, &Selection::new("table").in_region("kitchen")), 4);
        assert_eq!(pick(&m, &Selection::new("chair").in_region("Kitchen")), 14);
        let e = m
            .select(
                &Selection::new("table")
                    .colour("yellow")
                    .in_region("kitchen"),
                ORIGIN,
            )
            .unwrap_err();
        assert!(matches!(e, QueryError::NoSuchColour { .. }), "{e}");
        // The message says the room: the kitchen's one table is not all the tables.
        assert_eq!(
            e.to_string(),
            "there is no yellow table in the kitchen; the table in the kitchen is: 1 grey"
        );
    }

    #[test]
    fn an_excluded_colour_leaves_the_others() {
        let m = map();
        // "the table that isn't yellow": the nearest of black and grey
        assert_eq!(pick(&m, &Selection::new("table").not_colour("yellow")), 2);
        assert_eq!(
            pick(&m, &Selection::new("chair").not_colour("red")),
            13,
            "the only chair that is not red"
        );
        let e = m
            .select(
                &Selection::new("chair").colour("blue").not_colour("blue"),
                ORIGIN,
            )
            .unwrap_err();
        assert!(matches!(e, QueryError::NoSuchColour { .. }), "{e}");
        let yellow_only = Selection::new("table").colour("yellow").not_colour("black");
        assert_eq!(pick(&m, &yellow_only), 1);
        // the only table in the kitchen is grey: excluding grey leaves none
        let e = m
            .select(
                &Selection::new("table")
                    .in_region("kitchen")
                    .not_colour("grey"),
                ORIGIN,
            )
            .unwrap_err();
        assert_eq!(e.to_string(), "every table here is grey");
        let e = m
            .select(&Selection::new("table").not_colour("left"), ORIGIN)
            .unwrap_err();
        assert!(matches!(e, QueryError::NotAColour { .. }), "{e}");
    }

    #[test]
    fn the_other_one_leaves_out_the_instance_named() {
        let m = map();
        // "now the other red chair", after red chair 11: chair 14
        let other = Selection::new("chair").colour("red").other_than(11);
        assert_eq!(pick(&m, &other), 14);
        // after 14, the other red chair is 11 (the blue one is never a candidate)
        let other = Selection::new("chair").colour("red").other_than(14);
        assert_eq!(pick(&m, &other), 11);
        // "another table" after table 1: the nearest of the rest, and the ordinal
        // counts what is left ("the second other table")
        assert_eq!(pick(&m, &Selection::new("table").other_than(1)), 2);
        assert_eq!(pick(&m, &Selection::new("table").other_than(1).nth(2)), 3);
        assert_eq!(pick(&m, &Selection::new("table").other_than(1).nth(-1)), 4);
        // leaving out an instance the filters already left out changes nothing
        assert_eq!(
            pick(&m, &Selection::new("chair").colour("red").other_than(13)),
            11
        );
        // the one visited is the only blue chair: an error that says so
        let e = m
            .select(
                &Selection::new("chair").colour("blue").other_than(13),
                ORIGIN,
            )
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "there are 0 other blue chairs; asked for the 1st"
        );
        // an instance of another kind, or none at all: errors, never a silent pick
        let e = m
            .select(&Selection::new("chair").other_than(2), ORIGIN)
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "instance 2 is a table, not a chair; only a chair can be left out"
        );
        assert!(matches!(
            m.select(&Selection::new("chair").other_than(99), ORIGIN),
            Err(QueryError::UnknownInstance { id: 99 })
        ));
        // "between the two" with one left out: the two that remain
        let [a, b] = m
            .select_pair(
                &Selection::new("table").not_colour("grey").other_than(2),
                ORIGIN,
            )
            .unwrap();
        assert_eq!((a.id, b.id), (1, 3));
    }

    #[test]
    fn biggest_and_smallest_rank_by_footprint_area() {
        let m = map();
        let big = Selection::new("table")
            .ordered("largest_to_smallest")
            .unwrap();
        assert_eq!(pick(&m, &big), 4);
        assert_eq!(pick(&m, &big.clone().nth(2)), 1);
        let small = Selection::new("table")
            .ordered("smallest_to_largest")
            .unwrap();
        // tables 2 and 3 are the same size: the lower id first
        assert_eq!(pick(&m, &small), 2);
        assert_eq!(
            ObjectOrder::parse("largest to smallest").unwrap(),
            ObjectOrder::LargestToSmallest
        );
    }

    #[test]
    fn the_two_x_must_be_exactly_two() {
        let m = map();
        let [a, b] = m
            .select_pair(&Selection::new("table").colour("yellow"), ORIGIN)
            .unwrap();
        assert_eq!((a.id, b.id), (1, 3));
        let e = m.select_pair(&Selection::new("table"), ORIGIN).unwrap_err();
        assert_eq!(
            e.to_string(),
            "\"the two tables\" names 4 here, not 2 (ids 1, 2, 3, 4)"
        );
        let e = m
            .select_pair(&Selection::new("chair").colour("blue"), ORIGIN)
            .unwrap_err();
        assert!(
            matches!(e, QueryError::NotExactlyTwo { count: 1, .. }),
            "{e}"
        );
    }

    #[test]
    fn selections_read_and_write_json_with_defaults() {
        let s: Selection = serde_json::from_str(r#"{"name": "chair", "near": 4}"#).unwrap();
        assert_eq!(s, Selection::new("chair").near(4));
        let o: Selection = serde_json::from_str(r#"{"name": "chair", "other_than": 9}"#).unwrap();
        assert_eq!(o, Selection::new("chair").other_than(9));
        let back: Selection = serde_json::from_str(&serde_json::to_string(&s).unwrap()).unwrap();
        assert_eq!(back, s);
    }
}
