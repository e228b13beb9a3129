//! Conservative line of sight between cell centres: every cell the segment touches
//! (its supercover) must be free. Where the segment passes exactly through a cell
//! corner it touches all four cells there, so both side cells must be free too; this
//! is the same rule as an 8-connected step that may not cut a corner.

use super::{Padded, Passability};
use crate::grid::Cell;

/// Walk the cells the segment between the centres of `a` and `b` touches, from `a`
/// to `b`, calling `visit(row, col)`; stops early (returning false) when `visit`
/// returns false. At exact corner crossings the two side cells are visited before
/// the diagonal one.
fn walk(a: (i64, i64), b: (i64, i64), mut visit: impl FnMut(i64, i64) -> bool) -> bool {
    let (mut r, mut c) = a;
    let (dr, dc) = ((b.0 - a.0).abs(), (b.1 - a.1).abs());
    let (sr, sc) = ((b.0 - a.0).signum(), (b.1 - a.1).signum());
    // error = dc * (2 ny + 1) - dr * (2 nx + 1): sign tells which boundary comes first
    let mut err = dc - dr;
    let mut n = dr + dc;
    if !visit(r, c) {
        return false;
    }
    while n > 0 {
        if err > 0 {
            c += sc;
            err -= 2 * dr;
            n -= 1;
        } else if err < 0 {
            r += sr;
            err += 2 * dc;
            n -= 1;
        } else {
            if !visit(r, c + sc) || !visit(r + sr, c) {
                return false;
            }
            r += sr;
            c += sc;
            err += 2 * dc - 2 * dr;
            n -= 2;
        }
        if !visit(r, c) {
            return false;
        }
    }
    true
}

fn rc(c: Cell) -> (i64, i64) {
    (
        c.row.min(i64::MAX as usize / 4) as i64,
        c.col.min(i64::MAX as usize / 4) as i64,
    )
}

/// The cells the segment between the centres of `a` and `b` touches, from `a` to `b`.
pub fn supercover_cells(a: Cell, b: Cell) -> Vec<Cell> {
    let mut out = Vec::new();
    walk(rc(a), rc(b), |r, c| {
        out.push(Cell::new(r as usize, c as usize));
        true
    });
    out
}

/// Whether every cell the segment between the centres of `a` and `b` touches is free.
pub fn line_of_sight<P: Passability + ?Sized>(map: &P, a: Cell, b: Cell) -> bool {
    if !map.is_free(a) || !map.is_free(b) {
        return false;
    }
    walk(rc(a), rc(b), |r, c| {
        map.is_free(Cell::new(r as usize, c as usize))
    })
}

/// [`line_of_sight`] on a padded map between padded indices (both must be interior).
pub(crate) fn los_padded(map: &Padded, a: usize, b: usize) -> bool {
    let w = map.w as i64;
    let (ar, ac) = ((a as i64) / w, (a as i64) % w);
    let (br, bc) = ((b as i64) / w, (b as i64) % w);
    let (dr, dc) = ((br - ar).abs(), (bc - ac).abs());
    let (sr, sc) = ((br - ar).signum() * w, (bc - ac).signum());
    let free = &map.free;
    let mut i = a as i64;
    let mut err = dc - dr;
    let mut n = dr + dc;
    // padded indices of free cells and their neighbours stay inside the array; the
    // walk stops at the first blocked cell, so it never steps past the border
    let ok = |i: i64| free.get(i as usize).copied().unwrap_or(false);
    if !ok(i) {
        return false;
    }
    while n > 0 {
        if err > 0 {
            i += sc;
            err -= 2 * dr;
            n -= 1;
        } else if err < 0 {
            i += sr;
            err += 2 * dc;
            n -= 1;
        } else {
            if !ok(i + sc) || !ok(i + sr) {
                return false;
            }
            i += sr + sc;
            err += 2 * dc - 2 * dr;
            n -= 2;
        }
        if !ok(i) {
            return false;
        }
    }
    true
}

/// The thin cell sequence of the segment between padded indices `a` and `b` (the
/// supercover without the two side cells at exact corner crossings, so consecutive
/// cells are 8-neighbours), appended to `out` without `a` itself.
pub(crate) fn trace_padded(w: usize, a: usize, b: usize, out: &mut Vec<usize>) {
    let w = w as i64;
    let (ar, ac) = ((a as i64) / w, (a as i64) % w);
    let (br, bc) = ((b as i64) / w, (b as i64) % w);
    let (dr, dc) = ((br - ar).abs(), (bc - ac).abs());
    let (sr, sc) = ((br - ar).signum() * w, (bc - ac).signum());
    let mut i = a as i64;
    let mut err = dc - dr;
    let mut n = dr + dc;
    while n > 0 {
        if err > 0 {
            i += sc;
            err -= 2 * dr;
            n -= 1;
        } else if err < 0 {
            i += sr;
            err += 2 * dc;
            n -= 1;
        } else {
            i += sr + sc;
            err += 2 * dc - 2 * dr;
            n -= 2;
        }
        out.push(i as usize);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;

    #[test]
    fn supercover_includes_both_cells_at_a_corner_crossing() {
        let cells = supercover_cells(Cell::new(0, 0), Cell::new(2, 2));
        assert_eq!(cells.len(), 7);
        assert!(cells.contains(&Cell::new(0, 1)) && cells.contains(&Cell::new(1, 0)));
        let cells = supercover_cells(Cell::new(0, 0), Cell::new(1, 3));
        assert_eq!(
            cells,
            vec![
                Cell::new(0, 0),
                Cell::new(0, 1),
                Cell::new(1, 2),
                Cell::new(1, 3)
            ]
            .into_iter()
            .fold(Vec::new(), |mut v, c| {
                if c == Cell::new(1, 2) {
                    v.push(Cell::new(0, 2));
                    v.push(Cell::new(1, 1));
                }
                v.push(c);
                v
            })
        );
    }

    #[test]
    fn corner_touch_blocks_sight() {
        let mut g = Grid::new(3, 3, false);
        g.set(Cell::new(0, 1), true);
        assert!(!line_of_sight(&g, Cell::new(0, 0), Cell::new(1, 1)));
        assert!(line_of_sight(&g, Cell::new(1, 0), Cell::new(1, 2)));
        assert!(!line_of_sight(&g, Cell::new(0, 0), Cell::new(0, 2)));
        assert!(!line_of_sight(&g, Cell::new(0, 0), Cell::new(5, 5)));
    }
}
