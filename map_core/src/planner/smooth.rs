//! Any-angle smoothing of a cell path by line of sight (string pulling).
//!
//! Pass 1 walks the dense cell path and keeps a waypoint only where the cell after
//! it can no longer be seen from the last waypoint. The waypoints of pass 1 lie on
//! the grid path, which may run far from the obstacle corners the taut path bends
//! around, so the polyline is traced back into cells and pulled again; each round
//! moves the bends toward those corners. Rounds stop when the length stops falling.
//! Every kept segment passed the conservative line-of-sight test.

use super::line_of_sight::{los_padded, trace_padded};
use super::Padded;
use crate::grid::Cell;

const MAX_ROUNDS: usize = 8;

fn pull(map: &Padded, path: &[usize]) -> Vec<usize> {
    let Some(&first) = path.first() else {
        return Vec::new();
    };
    let mut out = vec![first];
    let mut anchor = first;
    for k in 1..path.len() {
        if !los_padded(map, anchor, path[k]) {
            // consecutive path cells always see each other, so path[k - 1] != anchor
            anchor = path[k - 1];
            out.push(anchor);
        }
    }
    if let Some(&last) = path.last() {
        if last != anchor {
            out.push(last);
        }
    }
    out
}

fn len(w: usize, pts: &[usize]) -> f64 {
    pts.windows(2)
        .map(|p| {
            let dr = (p[0] / w) as f64 - (p[1] / w) as f64;
            let dc = (p[0] % w) as f64 - (p[1] % w) as f64;
            dr.hypot(dc)
        })
        .sum()
}

/// Smooth a dense 8-connected path of padded indices into any-angle waypoints.
pub(crate) fn smooth(map: &Padded, dense: &[usize]) -> Vec<Cell> {
    let w = map.w;
    let mut best = pull(map, dense);
    let mut best_len = len(w, &best);
    let mut traced = Vec::new();
    for _ in 0..MAX_ROUNDS {
        if best.len() <= 2 {
            break;
        }
        traced.clear();
        traced.push(best[0]);
        for s in best.windows(2) {
            trace_padded(w, s[0], s[1], &mut traced);
        }
        let next = pull(map, &traced);
        let next_len = len(w, &next);
        if next_len >= best_len - 1e-9 {
            break;
        }
        best = next;
        best_len = next_len;
    }
    best.into_iter().map(|i| map.cell(i)).collect()
}
