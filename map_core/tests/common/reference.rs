//! Reference searches the planner is checked against (tests and benches share this
//! file): 8-connected moves without corner cutting, and the optimum from the
//! `pathfinding` crate's Dijkstra, independent of our jump point search.

use map_core::planner::MOVES8 as MOVES;
use map_core::{Cell, Grid};
use ordered_float::OrderedFloat;

/// Whether (r, c) is on the grid and free.
pub fn free(g: &Grid<bool>, r: isize, c: isize) -> bool {
    r >= 0 && c >= 0 && g.get(Cell::new(r as usize, c as usize)) == Some(&false)
}

/// Legal 8-connected moves: no corner cutting past an occupied cell.
pub fn neighbours(g: &Grid<bool>, cell: Cell) -> Vec<(Cell, f64)> {
    let (r, c) = (cell.row as isize, cell.col as isize);
    MOVES
        .iter()
        .filter(|&&(dr, dc)| {
            free(g, r + dr, c + dc)
                && (dr == 0 || dc == 0 || (free(g, r + dr, c) && free(g, r, c + dc)))
        })
        .map(|&(dr, dc)| {
            let cost = if dr != 0 && dc != 0 {
                std::f64::consts::SQRT_2
            } else {
                1.0
            };
            (Cell::new((r + dr) as usize, (c + dc) as usize), cost)
        })
        .collect()
}

/// The optimal path cost from `s` to `t` (octile), or `None` when `t` is unreachable.
pub fn dijkstra(g: &Grid<bool>, s: Cell, t: Cell) -> Option<f64> {
    pathfinding::prelude::dijkstra(
        &s,
        |&c| {
            neighbours(g, c)
                .into_iter()
                .map(|(n, w)| (n, OrderedFloat(w)))
        },
        |&c| c == t,
    )
    .map(|(_, cost)| cost.0)
}
