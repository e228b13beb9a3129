//! Property tests of the grid planner on random cluttered grids, each checked
//! against independent reference code written here: a breadth-first flood fill, a
//! Dijkstra (the `pathfinding` crate), an exact segment/square intersection test and brute-force
//! nearest-cell searches.

use std::collections::VecDeque;

use map_core::planner::{astar, inflate};
use map_core::{Cell, Grid, GridPlanner, PlanError};
use proptest::prelude::*;

#[path = "common/reference.rs"]
mod reference;
use reference::{dijkstra, neighbours};

fn flood(g: &Grid<bool>, s: Cell) -> Grid<bool> {
    let mut seen = Grid::new(g.rows(), g.cols(), false);
    let mut q = VecDeque::from([s]);
    seen.set(s, true);
    while let Some(c) = q.pop_front() {
        for (n, _) in neighbours(g, c) {
            if seen.get(n) == Some(&false) {
                seen.set(n, true);
                q.push_back(n);
            }
        }
    }
    seen
}

/// Exact test: does the segment between the centres of `a` and `b` touch the closed
/// square of `cell`? Coordinates doubled so that all corners are integers.
fn segment_touches(a: Cell, b: Cell, cell: Cell) -> bool {
    let (ar, ac, br, bc) = (
        2 * a.row as i64,
        2 * a.col as i64,
        2 * b.row as i64,
        2 * b.col as i64,
    );
    let (r0, r1, c0, c1) = (
        2 * cell.row as i64 - 1,
        2 * cell.row as i64 + 1,
        2 * cell.col as i64 - 1,
        2 * cell.col as i64 + 1,
    );
    if ar.max(br) < r0 || ar.min(br) > r1 || ac.max(bc) < c0 || ac.min(bc) > c1 {
        return false;
    }
    let side = |r: i64, c: i64| ((br - ar) * (c - ac) - (bc - ac) * (r - ar)).signum();
    let s = [side(r0, c0), side(r0, c1), side(r1, c0), side(r1, c1)];
    !(s.iter().all(|&x| x > 0) || s.iter().all(|&x| x < 0))
}

fn touched_cells(g: &Grid<bool>, a: Cell, b: Cell) -> Vec<Cell> {
    let mut out = Vec::new();
    for r in a.row.min(b.row).saturating_sub(1)..=(a.row.max(b.row) + 1).min(g.rows() - 1) {
        for c in a.col.min(b.col).saturating_sub(1)..=(a.col.max(b.col) + 1).min(g.cols() - 1) {
            if segment_touches(a, b, Cell::new(r, c)) {
                out.push(Cell::new(r, c));
            }
        }
    }
    out
}

fn d2(a: Cell, b: Cell) -> usize {
    a.row.abs_diff(b.row).pow(2) + a.col.abs_diff(b.col).pow(2)
}

/// A cluttered grid: random cells and random rectangles, optionally inflated.
fn grid_strategy() -> impl Strategy<Value = Grid<bool>> {
    sized_grid(36)
}

/// Grids up to `max` cells a side: above 62 columns (rows) the bit-parallel row
/// (column) scans of the jump point search cross 64-bit words.
fn sized_grid(max: usize) -> impl Strategy<Value = Grid<bool>> {
    (
        3usize..max,
        3usize..max,
        0.0f64..0.35,
        prop::collection::vec(
            (
                0usize..max,
                0usize..max,
                1usize..max / 4 + 2,
                1usize..max / 4 + 2,
            ),
            0..8,
        ),
        0u8..3,
        any::<u64>(),
    )
        .prop_map(|(rows, cols, density, rects, radius, seed)| {
            let mut g = Grid::new(rows, cols, false);
            let mut x = seed | 1;
            for i in 0..rows * cols {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                if (x % 10_000) as f64 / 10_000.0 < density {
                    g.as_mut_slice()[i] = true;
                }
            }
            for (r, c, h, w) in rects {
                for rr in r..(r + h).min(rows) {
                    for cc in c..(c + w).min(cols) {
                        g.set(Cell::new(rr, cc), true);
                    }
                }
            }
            if radius > 0 {
                inflate(&g, radius as f64)
            } else {
                g
            }
        })
}

fn cell_in(g: &Grid<bool>, r: usize, c: usize) -> Cell {
    Cell::new(r % g.rows(), c % g.cols())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn paths_are_optimal_safe_and_exist_iff_reachable(g in grid_strategy(), sr in 0usize..64, sc in 0usize..64, tr in 0usize..64, tc in 0usize..64) {
        let (s, t) = (cell_in(&g, sr, sc), cell_in(&g, tr, tc));
        prop_assume!(g.get(s) == Some(&false) && g.get(t) == Some(&false));
        let planner = GridPlanner::new(g.clone());
        let reachable = flood(&g, s).get(t) == Some(&true);
        match planner.plan(s, t) {
            Ok(p) => {
                prop_assert!(reachable, "found a path to an unreachable goal");
                prop_assert!(!p.start_snapped && !p.goal_snapped);
                prop_assert_eq!(p.waypoints.first(), Some(&s));
                prop_assert_eq!(p.waypoints.last(), Some(&t));
                let opt = dijkstra(&g, s, t).unwrap_or(f64::NAN);
                prop_assert!((p.raw_len - opt).abs() < 1e-9, "raw {} != Dijkstra {}", p.raw_len, opt);
                let a = astar(&g, s, t).map(|(_, c)| c).unwrap_or(f64::NAN);
                prop_assert!((a - opt).abs() < 1e-9, "astar {} != Dijkstra {}", a, opt);
                prop_assert!(p.smoothed_len <= p.raw_len + 1e-9, "smoothed {} > raw {}", p.smoothed_len, p.raw_len);
                for w in p.waypoints.windows(2) {
                    for cell in touched_cells(&g, w[0], w[1]) {
                        prop_assert!(g.get(cell) == Some(&false), "segment {:?} touches occupied {:?}", w, cell);
                    }
                }
            }
            Err(PlanError::Unreachable { goal, .. }) => {
                prop_assert!(!reachable, "missed a path");
                prop_assert_eq!(goal, t);
                prop_assert!(astar(&g, s, t).is_none());
            }
            Err(e) => prop_assert!(false, "unexpected error {e}"),
        }
    }

    #[test]
    fn snapping_picks_the_nearest_allowed_cell(g in grid_strategy(), sr in 0usize..64, sc in 0usize..64, tr in 0usize..64, tc in 0usize..64) {
        let (s, t) = (cell_in(&g, sr, sc), cell_in(&g, tr, tc));
        let planner = GridPlanner::new(g.clone());
        let frees: Vec<Cell> = g.iter_cells().filter(|(_, &o)| !o).map(|(c, _)| c).collect();
        let Some(best_s) = frees.iter().map(|&c| d2(c, s)).min() else {
            prop_assert_eq!(planner.plan(s, t), Err(PlanError::NoFreeCell));
            return Ok(());
        };
        let s_used = planner.nearest_free(s).unwrap();
        prop_assert_eq!(d2(s_used, s), best_s);
        let reach = flood(&g, s_used);
        let best_t = frees.iter().filter(|&&c| reach.get(c) == Some(&true)).map(|&c| d2(c, t)).min().unwrap();
        match planner.plan(s, t) {
            Ok(p) => {
                prop_assert_eq!(p.start, s_used);
                prop_assert_eq!(p.start_snapped, s != s_used);
                prop_assert_eq!(p.goal_snapped, p.goal != t);
                prop_assert!(reach.get(p.goal) == Some(&true));
                if g.get(t) == Some(&true) {
                    prop_assert_eq!(d2(p.goal, t), best_t);
                } else {
                    prop_assert_eq!(p.goal, t);
                }
            }
            Err(PlanError::Unreachable { goal, .. }) => {
                prop_assert_eq!(goal, t);
                prop_assert!(g.get(t) == Some(&false) && reach.get(t) == Some(&false));
            }
            Err(e) => prop_assert!(false, "unexpected error {e}"),
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 120, ..ProptestConfig::default() })]

    #[test]
    fn large_grids_match_dijkstra(g in sized_grid(200), sr in 0usize..400, sc in 0usize..400, tr in 0usize..400, tc in 0usize..400) {
        let (s, t) = (cell_in(&g, sr, sc), cell_in(&g, tr, tc));
        prop_assume!(g.get(s) == Some(&false) && g.get(t) == Some(&false));
        let planner = GridPlanner::new(g.clone());
        match (planner.plan(s, t), dijkstra(&g, s, t)) {
            (Ok(p), Some(opt)) => {
                prop_assert!((p.raw_len - opt).abs() < 1e-9, "raw {} != Dijkstra {}", p.raw_len, opt);
                for w in p.waypoints.windows(2) {
                    for cell in touched_cells(&g, w[0], w[1]) {
                        prop_assert!(g.get(cell) == Some(&false), "segment {:?} touches occupied {:?}", w, cell);
                    }
                }
            }
            (Err(PlanError::Unreachable { .. }), None) => {}
            (got, opt) => prop_assert!(false, "planner {got:?} vs Dijkstra {opt:?}"),
        }
    }
}
