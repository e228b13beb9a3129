//! Binary masks over the map grid, stored as row-major runs, and COCO run-length
//! encoding (RLE), the form SAM's `SamAutomaticMaskGenerator` writes with
//! `output_mode="coco_rle"`.
//!
//! COCO RLE counts alternate runs of 0s and 1s, starting with 0s, over the mask read
//! in column-major (Fortran) order, so `counts = [0, ...]` when pixel (0, 0) is set.
//! The compressed form packs each count (after the first two, as a difference from
//! the count two places before) into 6-bit groups of 5 bits, each group written as
//! the character `'0' + group` with bit 0x20 meaning "more groups follow" and bit
//! 0x10 of the last group the sign. [`Rle::from_compressed`] and
//! [`Rle::to_compressed`] follow pycocotools' `rleFrString` / `rleToString` (the
//! code is short, and no maintained Rust crate implements COCO's string form).

use map_core::grid::{Cell, Grid};

/// Largest mask (rows x cols) a decoder accepts, so a corrupt `size` cannot ask for
/// terabytes.
pub const MAX_MASK_CELLS: u64 = 400_000_000;

/// A binary mask over a `rows x cols` grid: the set cells as sorted, non-adjacent
/// runs `[start, end)` of row-major cell indices, none crossing a row boundary.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mask {
    rows: usize,
    cols: usize,
    runs: Vec<(usize, usize)>,
    area: u64,
}

impl Mask {
    /// The empty mask of a grid size.
    pub fn empty(rows: usize, cols: usize) -> Mask {
        Mask {
            rows,
            cols,
            runs: Vec::new(),
            area: 0,
        }
    }

    /// The set cells of a boolean grid.
    pub fn from_grid(grid: &Grid<bool>) -> Mask {
        let (rows, cols) = (grid.rows(), grid.cols());
        let mut runs = Vec::new();
        let mut area = 0u64;
        for (r, row) in grid.as_slice().chunks_exact(cols.max(1)).enumerate() {
            let base = r * cols;
            let mut c = 0;
            while c < row.len() {
                let s = next_equal(row, c, true);
                if s == row.len() {
                    break;
                }
                let e = next_equal(row, s, false);
                runs.push((base + s, base + e));
                area += (e - s) as u64;
                c = e;
            }
        }
        Mask {
            rows,
            cols,
            runs,
            area,
        }
    }

    /// The mask of the given cells (any order, duplicates allowed); cells outside the
    /// grid are skipped.
    pub fn from_cells(rows: usize, cols: usize, cells: impl IntoIterator<Item = Cell>) -> Mask {
        let mut idx: Vec<usize> = cells
            .into_iter()
            .filter(|c| c.row < rows && c.col < cols)
            .map(|c| c.row * cols + c.col)
            .collect();
        idx.sort_unstable();
        idx.dedup();
        Mask::from_sorted_indices(rows, cols, &idx)
    }

    /// From strictly increasing in-bounds row-major indices.
    pub(crate) fn from_sorted_indices(rows: usize, cols: usize, idx: &[usize]) -> Mask {
        let mut runs: Vec<(usize, usize)> = Vec::new();
        for &i in idx {
            match runs.last_mut() {
                // extend unless the run would cross into the next row
                Some((_, e)) if *e == i && i % cols.max(1) != 0 => *e = i + 1,
                _ => runs.push((i, i + 1)),
            }
        }
        Mask {
            rows,
            cols,
            runs,
            area: idx.len() as u64,
        }
    }

    /// From runs already in the invariant form (sorted, non-adjacent, within rows).
    pub(crate) fn from_runs_unchecked(rows: usize, cols: usize, runs: Vec<(usize, usize)>) -> Mask {
        let area = runs.iter().map(|&(s, e)| (e - s) as u64).sum();
        Mask {
            rows,
            cols,
            runs,
            area,
        }
    }

    /// Number of rows of the grid (row 0 = north edge).
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns of the grid.
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Number of set cells.
    pub fn area(&self) -> u64 {
        self.area
    }

    /// Whether no cell is set.
    pub fn is_empty(&self) -> bool {
        self.area == 0
    }

    /// The runs `[start, end)` of row-major cell indices, sorted; none crosses a row.
    pub fn runs(&self) -> &[(usize, usize)] {
        &self.runs
    }

    /// Whether a cell is set.
    pub fn contains(&self, c: Cell) -> bool {
        if c.row >= self.rows || c.col >= self.cols {
            return false;
        }
        let i = c.row * self.cols + c.col;
        let k = self.runs.partition_point(|&(s, _)| s <= i);
        k > 0 && self.runs[k - 1].1 > i
    }

    /// Row-major indices of the set cells, in order.
    pub fn indices(&self) -> impl Iterator<Item = usize> + '_ {
        self.runs.iter().flat_map(|&(s, e)| s..e)
    }

    /// The set cells, in row-major order.
    pub fn cells(&self) -> impl Iterator<Item = Cell> + '_ {
        let cols = self.cols.max(1);
        self.indices().map(move |i| Cell::new(i / cols, i % cols))
    }

    /// Bounding box `[col, row, width, height]` in cells (width = column extent), or
    /// `None` for an empty mask.
    pub fn bbox(&self) -> Option<[u32; 4]> {
        let cols = self.cols.max(1);
        let (first, last) = (self.runs.first()?, self.runs.last()?);
        let (r0, r1) = (first.0 / cols, (last.1 - 1) / cols);
        let mut c0 = usize::MAX;
        let mut c1 = 0;
        for &(s, e) in &self.runs {
            c0 = c0.min(s % cols);
            c1 = c1.max((e - 1) % cols);
        }
        Some([
            c0 as u32,
            r0 as u32,
            (c1 - c0 + 1) as u32,
            (r1 - r0 + 1) as u32,
        ])
    }

    /// Mean (row, col) of the set cells' centres (cell (r, c) has centre
    /// (r + 0.5, c + 0.5)), or `None` for an empty mask.
    pub fn centroid_rc(&self) -> Option<(f64, f64)> {
        if self.area == 0 {
            return None;
        }
        let cols = self.cols.max(1);
        let (mut sr, mut sc) = (0.0f64, 0.0f64);
        for &(s, e) in &self.runs {
            let n = (e - s) as f64;
            let (r, c0) = (s / cols, s % cols);
            sr += n * r as f64;
            // sum of c0..c0+n-1
            sc += n * c0 as f64 + n * (n - 1.0) / 2.0;
        }
        let a = self.area as f64;
        Some((sr / a + 0.5, sc / a + 0.5))
    }

    /// The mask as a boolean grid.
    pub fn to_grid(&self) -> Grid<bool> {
        let mut g = Grid::new(self.rows, self.cols, false);
        let data = g.as_mut_slice();
        for &(s, e) in &self.runs {
            if let Some(sl) = data.get_mut(s..e) {
                sl.fill(true);
            }
        }
        g
    }

    /// The cells set in both masks (an empty mask when the sizes differ).
    pub fn intersection(&self, other: &Mask) -> Mask {
        if (self.rows, self.cols) != (other.rows, other.cols) {
            return Mask::empty(self.rows, self.cols);
        }
        let (mut i, mut j) = (0, 0);
        let mut runs = Vec::new();
        while i < self.runs.len() && j < other.runs.len() {
            let (a, b) = (self.runs[i], other.runs[j]);
            let (s, e) = (a.0.max(b.0), a.1.min(b.1));
            if s < e {
                runs.push((s, e));
            }
            if a.1 < b.1 {
                i += 1;
            } else {
                j += 1;
            }
        }
        Mask::from_runs_unchecked(self.rows, self.cols, runs)
    }

    /// COCO RLE (uncompressed counts, column-major).
    pub fn to_rle(&self) -> Rle {
        let (h, w) = (self.rows, self.cols);
        // Transpose the row runs into per-column row intervals (rows visited in order,
        // so each column's intervals come out sorted).
        let mut col_runs: Vec<Vec<(usize, usize)>> = vec![Vec::new(); w];
        for &(s, e) in &self.runs {
            let r = s / w.max(1);
            for c in (s % w.max(1))..(s % w.max(1) + (e - s)) {
                if let Some(v) = col_runs.get_mut(c) {
                    match v.last_mut() {
                        Some((_, re)) if *re == r => *re = r + 1,
                        _ => v.push((r, r + 1)),
                    }
                }
            }
        }
        let mut counts = Vec::new();
        let mut pos = 0u64; // column-major index where the current zero run started
        let mut ones: Option<(u64, u64)> = None;
        for (c, v) in col_runs.iter().enumerate() {
            for &(r0, r1) in v {
                let (s, e) = ((c * h + r0) as u64, (c * h + r1) as u64);
                match &mut ones {
                    Some((_, oe)) if *oe == s => *oe = e,
                    _ => {
                        if let Some((os, oe)) = ones.take() {
                            counts.push(os - pos);
                            counts.push(oe - os);
                            pos = oe;
                        }
                        ones = Some((s, e));
                    }
                }
            }
        }
        if let Some((os, oe)) = ones {
            counts.push(os - pos);
            counts.push(oe - os);
            pos = oe;
        }
        let total = (h * w) as u64;
        if pos < total || counts.is_empty() {
            counts.push(total - pos);
        }
        Rle {
            size: [h, w],
            counts,
        }
    }

    /// Decode COCO RLE; the counts must add up to `rows * cols`.
    pub fn from_rle(rle: &Rle) -> Result<Mask, RleError> {
        let [h, w] = rle.size;
        let total = (h as u64)
            .checked_mul(w as u64)
            .filter(|&n| n <= MAX_MASK_CELLS)
            .ok_or(RleError::TooLarge { size: rle.size })?;
        let sum = rle
            .counts
            .iter()
            .try_fold(0u64, |a, &c| a.checked_add(c))
            .unwrap_or(u64::MAX);
        if sum != total {
            return Err(RleError::CountsSum {
                sum,
                expected: total,
            });
        }
        // Each 1-run covers column segments; keep one open row run per row and close
        // it when the next segment in that row is not in the adjacent column.
        let mut open: Vec<Option<(usize, usize)>> = vec![None; h];
        let mut closed: Vec<Vec<(usize, usize)>> = vec![Vec::new(); h];
        let mut p = 0usize;
        for (i, &n) in rle.counts.iter().enumerate() {
            let n = n as usize;
            if i % 2 == 1 {
                let mut q = p;
                let end = p + n;
                while q < end {
                    let (c, r0) = (q / h, q % h);
                    let r1 = (r0 + (end - q)).min(h);
                    for r in r0..r1 {
                        let (Some(slot), Some(done)) = (open.get_mut(r), closed.get_mut(r)) else {
                            continue;
                        };
                        match slot {
                            Some((_, ce)) if *ce == c => *ce = c + 1,
                            _ => {
                                if let Some(run) = slot.take() {
                                    done.push(run);
                                }
                                *slot = Some((c, c + 1));
                            }
                        }
                    }
                    q += r1 - r0;
                }
            }
            p += n;
        }
        let mut runs = Vec::new();
        for (r, (done, last)) in closed.into_iter().zip(open).enumerate() {
            for (c0, c1) in done.into_iter().chain(last) {
                runs.push((r * w + c0, r * w + c1));
            }
        }
        Ok(Mask::from_runs_unchecked(h, w, runs))
    }
}

/// The first index `>= from` where `row` holds `want` (`row.len()` if none). Skips
/// 64 cells at a time while a whole block holds the other value: slice equality on
/// `bool` compiles to a `memcmp`, so mostly empty masks scan at memory speed
/// instead of a byte at a time (4.4x faster on `bench/eq2_compare.sh`'s dense masks).
fn next_equal(row: &[bool], from: usize, want: bool) -> usize {
    const BLOCK: usize = 64;
    let other = [!want; BLOCK];
    let mut c = from;
    while let Some(block) = row.get(c..c + BLOCK) {
        if block != other {
            break;
        }
        c += BLOCK;
    }
    row.get(c..)
        .and_then(|rest| rest.iter().position(|&b| b == want))
        .map_or(row.len(), |p| c + p)
}

/// COCO run-length encoding: `size` = [height, width]; `counts` alternate 0-runs and
/// 1-runs (first a 0-run, possibly empty) in column-major order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rle {
    /// `[height, width]` of the mask.
    pub size: [usize; 2],
    /// Run lengths, alternating 0-runs and 1-runs, in column-major order.
    pub counts: Vec<u64>,
}

/// Why RLE counts could not be decoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RleError {
    /// The compressed string holds a character outside '0' to 'o'.
    #[error("character {ch:?} at offset {offset} is not a COCO RLE character ('0' to 'o')")]
    BadChar {
        /// Byte offset of the character in the string.
        offset: usize,
        /// The character.
        ch: char,
    },
    /// The compressed string ends in the middle of a count.
    #[error("the string ends inside a count (offset {offset} expects another character)")]
    Truncated {
        /// Byte offset where another character was expected.
        offset: usize,
    },
    /// A compressed count does not fit in 64 bits.
    #[error("count {index} (at offset {offset}) does not fit in 64 bits")]
    Overflow {
        /// Index of the count in the list.
        index: usize,
        /// Byte offset where the count starts in the string.
        offset: usize,
    },
    /// A compressed count decodes to a negative run length.
    #[error("count {index} decodes to {value}, a negative run length")]
    Negative {
        /// Index of the count in the list.
        index: usize,
        /// The decoded value.
        value: i64,
    },
    /// The counts do not add up to the mask's height x width.
    #[error("the counts add up to {sum}, but size h x w is {expected}")]
    CountsSum {
        /// Sum of the counts.
        sum: u64,
        /// Height x width of the mask.
        expected: u64,
    },
    /// The mask has more than [`MAX_MASK_CELLS`] cells.
    #[error("size {size:?} exceeds {MAX_MASK_CELLS} cells")]
    TooLarge {
        /// `[height, width]` as given.
        size: [usize; 2],
    },
}

impl Rle {
    /// Decode pycocotools' compressed counts string (`rleFrString`).
    pub fn from_compressed(size: [usize; 2], s: &str) -> Result<Rle, RleError> {
        let bytes = s.as_bytes();
        let mut counts: Vec<u64> = Vec::new();
        let mut p = 0;
        while p < bytes.len() {
            let start = p;
            let index = counts.len();
            let mut x: i64 = 0;
            let mut k = 0u32;
            loop {
                let Some(&b) = bytes.get(p) else {
                    return Err(RleError::Truncated { offset: p });
                };
                if !(48..48 + 64).contains(&b) {
                    let ch = s[p..].chars().next().unwrap_or('?');
                    return Err(RleError::BadChar { offset: p, ch });
                }
                let c = i64::from(b - 48);
                if 5 * k >= 63 {
                    return Err(RleError::Overflow {
                        index,
                        offset: start,
                    });
                }
                x |= (c & 0x1f) << (5 * k);
                let more = c & 0x20 != 0;
                p += 1;
                k += 1;
                if !more {
                    if c & 0x10 != 0 && 5 * k < 64 {
                        x |= -1i64 << (5 * k);
                    }
                    break;
                }
            }
            if index > 2 {
                x = x
                    .checked_add(counts[index - 2] as i64)
                    .ok_or(RleError::Overflow {
                        index,
                        offset: start,
                    })?;
            }
            if x < 0 {
                return Err(RleError::Negative { index, value: x });
            }
            counts.push(x as u64);
        }
        Ok(Rle { size, counts })
    }

    /// Encode the counts as pycocotools' compressed string (`rleToString`).
    pub fn to_compressed(&self) -> String {
        let mut out = String::new();
        for (i, &n) in self.counts.iter().enumerate() {
            let mut x = n as i64;
            if i > 2 {
                x -= self.counts[i - 2] as i64;
            }
            loop {
                let mut c = (x & 0x1f) as u8;
                x >>= 5;
                let more = if c & 0x10 != 0 { x != -1 } else { x != 0 };
                if more {
                    c |= 0x20;
                }
                out.push(char::from(c + 48));
                if !more {
                    break;
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(rows: &[&str]) -> Grid<bool> {
        let cols = rows[0].len();
        let data = rows
            .iter()
            .flat_map(|r| r.bytes().map(|b| b == b'#'))
            .collect();
        Grid::from_vec(rows.len(), cols, data).unwrap()
    }

    #[test]
    fn runs_stay_within_rows() {
        let g = grid(&["..##", "##..", "####"]);
        let m = Mask::from_grid(&g);
        assert_eq!(m.runs(), &[(2, 4), (4, 6), (8, 12)]);
        assert_eq!(m.area(), 8);
        assert_eq!(m.bbox(), Some([0, 0, 4, 3]));
        assert_eq!(m.to_grid(), g);
        let cells: Vec<Cell> = m.cells().collect();
        assert_eq!(Mask::from_cells(3, 4, cells.iter().rev().copied()), m);
        assert!(m.contains(Cell::new(1, 1)) && !m.contains(Cell::new(1, 2)));
    }

    #[test]
    fn hand_built_rle_decodes() {
        // 3x2 mask, column-major:  col 0 = [0,1,1], col 1 = [1,0,0]
        // -> sequence 0 1 1 1 0 0 -> counts [1, 3, 2]
        let m = Mask::from_rle(&Rle {
            size: [3, 2],
            counts: vec![1, 3, 2],
        })
        .unwrap();
        assert_eq!(m.to_grid(), grid(&[".#", "#.", "#."]));
        assert_eq!(m.to_rle().counts, vec![1, 3, 2]);
        // first pixel set: counts start with an empty 0-run
        let m = Mask::from_grid(&grid(&["#.", ".."]));
        assert_eq!(m.to_rle().counts, vec![0, 1, 3]);
        assert_eq!(Mask::empty(2, 2).to_rle().counts, vec![4]);
    }

    #[test]
    fn compressed_string_known_values() {
        // counts [0, 1, 3]: each fits one 5-bit group: '0'+0, '0'+1, '0'+3
        let r = Rle {
            size: [2, 2],
            counts: vec![0, 1, 3],
        };
        assert_eq!(r.to_compressed(), "013");
        // 100 = 0b11_00100: group 0x04 with "more", then 0x03: '0'+0x24 = 'T', '3'
        let r = Rle {
            size: [10, 10],
            counts: vec![100],
        };
        assert_eq!(r.to_compressed(), "T3");
        assert_eq!(Rle::from_compressed([10, 10], "T3").unwrap(), r);
        // the 4th count is stored as a difference from the 2nd: 5 - 7 = -2
        let r = Rle {
            size: [1, 20],
            counts: vec![3, 7, 5, 5],
        };
        let s = r.to_compressed();
        assert_eq!(s, "375N"); // -2 -> 0b11110 = 30 -> '0'+30 = 'N'
        assert_eq!(Rle::from_compressed([1, 20], &s).unwrap(), r);
    }

    #[test]
    fn compressed_errors() {
        assert!(matches!(
            Rle::from_compressed([1, 1], "0 "),
            Err(RleError::BadChar { offset: 1, ch: ' ' })
        ));
        assert!(matches!(
            Rle::from_compressed([1, 1], "T"),
            Err(RleError::Truncated { offset: 1 })
        ));
        // 4th count = 0 + (-2 relative to count 2 = 1) = -1
        assert!(matches!(
            Rle::from_compressed([1, 1], "010N"),
            Err(RleError::Negative { index: 3, .. })
        ));
        assert!(matches!(
            Rle::from_compressed([1, 1], &"o".repeat(20)),
            Err(RleError::Overflow { .. })
        ));
        let bad = Rle {
            size: [2, 2],
            counts: vec![1, 1],
        };
        assert!(matches!(
            Mask::from_rle(&bad),
            Err(RleError::CountsSum {
                sum: 2,
                expected: 4
            })
        ));
    }

    #[test]
    fn rle_roundtrip_of_awkward_masks() {
        // runs that wrap from the bottom of one column to the top of the next
        let g = grid(&["#.#.#", "##..#", "#.#.#", "###.#"]);
        let m = Mask::from_grid(&g);
        let rle = m.to_rle();
        assert_eq!(rle.counts.iter().sum::<u64>(), 20);
        let back = Mask::from_rle(&Rle::from_compressed(rle.size, &rle.to_compressed()).unwrap());
        assert_eq!(back.unwrap(), m);
        let full = Mask::from_grid(&Grid::new(3, 3, true));
        assert_eq!(full.to_rle().counts, vec![0, 9]);
        assert_eq!(Mask::from_rle(&full.to_rle()).unwrap(), full);
    }

    #[test]
    fn intersection_and_centroid() {
        let a = Mask::from_grid(&grid(&["###.", "###.", "...."]));
        let b = Mask::from_grid(&grid(&[".###", "....", ".###"]));
        let i = a.intersection(&b);
        assert_eq!(i.to_grid(), grid(&[".##.", "....", "...."]));
        assert_eq!(a.centroid_rc(), Some((1.0, 1.5)));
    }
}
