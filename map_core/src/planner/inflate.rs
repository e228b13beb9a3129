//! Obstacle inflation by the robot radius: dilation with a disk.

use crate::grid::Grid;

/// Dilate the occupied cells (`true`) of `obstacles` by a disk of `radius_cells`:
/// a cell becomes occupied when an occupied cell's centre lies within the radius of
/// its centre (`dr² + dc² <= r²`). A radius below 0.5 or not finite changes nothing
/// (a NaN or negative radius is treated as 0; an infinite one as the grid's diagonal).
pub fn inflate(obstacles: &Grid<bool>, radius_cells: f64) -> Grid<bool> {
    let (rows, cols) = (obstacles.rows(), obstacles.cols());
    let diag = ((rows * rows + cols * cols) as f64).sqrt() + 1.0;
    let r = if radius_cells.is_nan() || radius_cells < 0.0 {
        0.0
    } else {
        radius_cells.min(diag)
    };
    let rr = r.floor() as usize;
    if rr == 0 || rows == 0 || cols == 0 {
        return obstacles.clone();
    }
    // half-width of the disk on row offset dr
    let half: Vec<usize> = (0..=rr)
        .map(|dr| (r * r - (dr * dr) as f64).max(0.0).sqrt().floor() as usize)
        .collect();
    // per-row prefix counts of occupied cells: "any occupied in [c - w, c + w]" in O(1)
    let src = obstacles.as_slice();
    let mut prefix = vec![0u32; rows * (cols + 1)];
    for r in 0..rows {
        let (row, pre) = (
            &src[r * cols..(r + 1) * cols],
            &mut prefix[r * (cols + 1)..(r + 1) * (cols + 1)],
        );
        for c in 0..cols {
            pre[c + 1] = pre[c] + u32::from(row[c]);
        }
    }
    let mut out = vec![false; rows * cols];
    for r in 0..rows {
        let dst = &mut out[r * cols..(r + 1) * cols];
        for (dr, &w) in half.iter().enumerate() {
            for sr in [r.checked_sub(dr), if dr == 0 { None } else { Some(r + dr) }]
                .into_iter()
                .flatten()
            {
                if sr >= rows {
                    continue;
                }
                let pre = &prefix[sr * (cols + 1)..(sr + 1) * (cols + 1)];
                if pre[cols] == 0 {
                    continue;
                }
                for (c, d) in dst.iter_mut().enumerate() {
                    if !*d {
                        let lo = c.saturating_sub(w);
                        let hi = (c + w + 1).min(cols);
                        *d = pre[hi] > pre[lo];
                    }
                }
            }
        }
    }
    Grid::from_vec(rows, cols, out).unwrap_or_else(|| obstacles.clone())
}

/// [`inflate`] with the radius in metres on cells of `cell_size` metres.
pub fn inflate_m(obstacles: &Grid<bool>, radius_m: f64, cell_size: f64) -> Grid<bool> {
    if cell_size.is_nan() || cell_size <= 0.0 || !cell_size.is_finite() {
        return obstacles.clone();
    }
    inflate(obstacles, radius_m / cell_size)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Cell;

    #[test]
    fn single_cell_grows_into_a_disk() {
        let mut g = Grid::new(11, 11, false);
        g.set(Cell::new(5, 5), true);
        let out = inflate(&g, 3.0);
        for (c, &occ) in out.iter_cells() {
            let (dr, dc) = (c.row as i64 - 5, c.col as i64 - 5);
            assert_eq!(occ, dr * dr + dc * dc <= 9, "cell {c:?}");
        }
        // (3,0) in, (2,2) in (8 <= 9), (2,3) out (13 > 9)
        assert!(out.get(Cell::new(8, 5)) == Some(&true) && out.get(Cell::new(7, 7)) == Some(&true));
        assert_eq!(out.get(Cell::new(7, 8)), Some(&false));
        assert_eq!(out.as_slice().iter().filter(|&&b| b).count(), 29);
    }

    #[test]
    fn radius_in_metres_and_degenerate_radii() {
        let mut g = Grid::new(7, 7, false);
        g.set(Cell::new(0, 0), true);
        let out = inflate_m(&g, 0.1, 0.05);
        assert_eq!(out.as_slice().iter().filter(|&&b| b).count(), 6); // quarter disk r=2: (0,0),(0,1),(0,2),(1,0),(1,1),(2,0)
        assert_eq!(inflate(&g, 0.4), g);
        assert_eq!(inflate(&g, f64::NAN), g);
        assert_eq!(inflate(&g, -3.0), g);
        assert!(inflate(&g, f64::INFINITY).as_slice().iter().all(|&b| b));
        assert_eq!(inflate_m(&g, 1.0, 0.0), g);
    }
}
