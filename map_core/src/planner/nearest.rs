//! Nearest cell (Euclidean distance between centres) that satisfies a test.

use super::Padded;
use crate::grid::Cell;

/// The cell nearest to `target` (which may lie outside the grid) whose padded index
/// passes `ok`; ties go to the first in row-major order. Searches square rings of
/// growing Chebyshev radius and stops once no nearer cell can exist.
pub(crate) fn nearest(map: &Padded, target: Cell, ok: impl Fn(usize) -> bool) -> Option<Cell> {
    if map.rows == 0 || map.cols == 0 {
        return None;
    }
    let (rows, cols) = (map.rows as i64, map.cols as i64);
    // far-away targets are pulled in (keeps k * k from overflowing; the answer only
    // changes among cells at nearly equal distance from such a target)
    let far = 2 * (rows + cols);
    let tr = i64::try_from(target.row).unwrap_or(far).min(far);
    let tc = i64::try_from(target.col).unwrap_or(far).min(far);
    // distance from the target to the grid: rings below this radius are empty
    let gap = |t: i64, n: i64| if t >= n { t - (n - 1) } else { 0 };
    let k0 = gap(tr, rows).max(gap(tc, cols));
    let kmax = k0 + rows + cols;
    let mut best: Option<(i64, i64, i64)> = None; // (d2, r, c)
    let consider = |r: i64, c: i64, best: &mut Option<(i64, i64, i64)>| {
        if r < 0 || c < 0 || r >= rows || c >= cols {
            return;
        }
        let i = (r as usize + 1) * map.w + c as usize + 1;
        if !ok(i) {
            return;
        }
        let d2 = (r - tr) * (r - tr) + (c - tc) * (c - tc);
        if best.is_none_or(|(bd, br, bc)| (d2, r, c) < (bd, br, bc)) {
            *best = Some((d2, r, c));
        }
    };
    for k in k0..=kmax {
        if let Some((bd, _, _)) = best {
            if k * k > bd {
                break;
            }
        }
        if k == 0 {
            consider(tr, tc, &mut best);
            continue;
        }
        // clip the ring's sides to the grid to skip cells outside
        let (c_lo, c_hi) = ((tc - k).max(0), (tc + k).min(cols - 1));
        for r in [tr - k, tr + k] {
            if (0..rows).contains(&r) {
                for c in c_lo..=c_hi {
                    consider(r, c, &mut best);
                }
            }
        }
        let (r_lo, r_hi) = ((tr - k + 1).max(0), (tr + k - 1).min(rows - 1));
        for c in [tc - k, tc + k] {
            if (0..cols).contains(&c) {
                for r in r_lo..=r_hi {
                    consider(r, c, &mut best);
                }
            }
        }
    }
    best.map(|(_, r, c)| Cell::new(r as usize, c as usize))
}
