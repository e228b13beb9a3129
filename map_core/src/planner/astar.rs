//! Plain A* over any [`Passability`] map: 8-connected, octile costs and heuristic,
//! no corner cutting. A reference for the jump point search and a planner for maps
//! that are not worth preprocessing.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::{octile, Passability};
use crate::grid::Cell;

/// The optimal 8-connected cell path from `start` to `goal` and its length in
/// cells, or `None` when either is blocked or out of bounds or no path exists.
pub fn astar<P: Passability + ?Sized>(
    map: &P,
    start: Cell,
    goal: Cell,
) -> Option<(Vec<Cell>, f64)> {
    if !map.is_free(start) || !map.is_free(goal) {
        return None;
    }
    let (rows, cols) = (map.rows(), map.cols());
    let n = rows.checked_mul(cols)?;
    let idx = |c: Cell| c.row * cols + c.col;
    let mut g = vec![f64::INFINITY; n];
    let mut parent = vec![usize::MAX; n];
    let mut closed = vec![false; n];
    let mut heap = BinaryHeap::new();
    g[idx(start)] = 0.0;
    heap.push(Reverse((octile(start, goal).to_bits(), idx(start))));
    let free =
        |r: isize, c: isize| r >= 0 && c >= 0 && map.is_free(Cell::new(r as usize, c as usize));
    while let Some(Reverse((_, i))) = heap.pop() {
        if closed[i] {
            continue;
        }
        closed[i] = true;
        let cell = Cell::new(i / cols, i % cols);
        if cell == goal {
            let mut path = vec![cell];
            let mut k = i;
            while parent[k] != usize::MAX {
                k = parent[k];
                path.push(Cell::new(k / cols, k % cols));
            }
            path.reverse();
            return Some((path, g[i]));
        }
        let (r, c) = (cell.row as isize, cell.col as isize);
        for (dr, dc) in super::MOVES8 {
            let (nr, nc) = (r + dr, c + dc);
            if !free(nr, nc) || (dr != 0 && dc != 0 && !(free(r + dr, c) && free(r, c + dc))) {
                continue;
            }
            let j = nr as usize * cols + nc as usize;
            if closed[j] {
                continue;
            }
            let ng = g[i]
                + if dr != 0 && dc != 0 {
                    std::f64::consts::SQRT_2
                } else {
                    1.0
                };
            if ng < g[j] {
                g[j] = ng;
                parent[j] = i;
                let h = octile(Cell::new(nr as usize, nc as usize), goal);
                heap.push(Reverse(((ng + h).to_bits(), j)));
            }
        }
    }
    None
}
