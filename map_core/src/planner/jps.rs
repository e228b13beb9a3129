//! Jump point search: optimal 8-connected grid search (octile costs, no corner
//! cutting) that expands only jump points. It returns the same path cost as A*
//! and Dijkstra on the same moves; the property tests check that.
//!
//! Rules for the no-corner-cutting variant: a diagonal step needs both orthogonal
//! neighbours free; a straight jump stops where a side cell opens up behind a wall
//! (side free, side-behind blocked); a diagonal jump stops where either of its
//! straight sub-jumps finds a jump point.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::Padded;

const SQRT2: f64 = std::f64::consts::SQRT_2;

/// Reusable per-search arrays, valid for one map size; entries are valid only when
/// their stamp matches the current search's generation.
#[derive(Debug)]
pub(crate) struct Scratch {
    g: Vec<f64>,
    parent: Vec<u32>,
    /// 2 * gen = seen (open), 2 * gen + 1 = closed
    stamp: Vec<u32>,
    gen: u32,
    heap: BinaryHeap<Reverse<(u64, u32)>>,
}

impl Scratch {
    pub fn new(n: usize) -> Self {
        Self {
            g: vec![0.0; n],
            parent: vec![0; n],
            stamp: vec![0; n],
            gen: 0,
            heap: BinaryHeap::new(),
        }
    }

    fn next_gen(&mut self) {
        if self.gen >= u32::MAX / 2 - 1 {
            self.stamp.iter_mut().for_each(|s| *s = 0);
            self.gen = 0;
        }
        self.gen += 1;
        self.heap.clear();
    }
}

#[inline]
fn step(i: usize, d: isize) -> usize {
    i.wrapping_add_signed(d)
}

/// Free cells as bits, one bit line per padded row (or per padded column for the
/// transposed copy): straight jumps test 64 cells at a time.
#[derive(Debug, Clone)]
pub(crate) struct Lines {
    wpl: usize,
    bits: Vec<u64>,
}

impl Lines {
    /// `n_lines` lines of `len` bits; bit k of line l is `f(l, k)`.
    pub fn build(n_lines: usize, len: usize, f: impl Fn(usize, usize) -> bool) -> Self {
        let wpl = len / 64 + 1;
        let mut bits = vec![0u64; n_lines * wpl];
        for l in 0..n_lines {
            for k in 0..len {
                if f(l, k) {
                    bits[l * wpl + k / 64] |= 1 << (k % 64);
                }
            }
        }
        Self { wpl, bits }
    }

    #[inline]
    fn word(&self, l: usize, wi: usize) -> u64 {
        if wi >= self.wpl {
            return 0;
        }
        self.bits.get(l * self.wpl + wi).copied().unwrap_or(0)
    }

    /// First stop after `pos` moving up line `l`: a blocked cell (None) or a cell
    /// where a neighbour line opens up behind a wall (Some), or `goal` if sooner.
    #[inline]
    fn scan_up(&self, l: usize, pos: usize, goal: Option<usize>) -> Option<usize> {
        let mut wi = pos / 64;
        let b0 = pos % 64;
        let mut mask = if b0 == 63 { 0 } else { !0u64 << (b0 + 1) };
        while wi < self.wpl {
            let (b, u, d) = (self.word(l, wi), self.word(l - 1, wi), self.word(l + 1, wi));
            let (pu, pd) = if wi == 0 {
                (0, 0)
            } else {
                (
                    self.word(l - 1, wi - 1) >> 63,
                    self.word(l + 1, wi - 1) >> 63,
                )
            };
            let stop = (!b | (u & !((u << 1) | pu)) | (d & !((d << 1) | pd))) & mask;
            if stop != 0 {
                let x = wi * 64 + stop.trailing_zeros() as usize;
                if let Some(g) = goal {
                    if g > pos && g <= x {
                        return Some(g);
                    }
                }
                return if (b >> (x % 64)) & 1 == 1 {
                    Some(x)
                } else {
                    None
                };
            }
            wi += 1;
            mask = !0;
        }
        None
    }

    /// As [`Lines::scan_up`], moving down line `l` from `pos`.
    #[inline]
    fn scan_down(&self, l: usize, pos: usize, goal: Option<usize>) -> Option<usize> {
        let mut wi = pos / 64;
        let mut mask = (1u64 << (pos % 64)) - 1;
        loop {
            let (b, u, d) = (self.word(l, wi), self.word(l - 1, wi), self.word(l + 1, wi));
            let (nu, nd) = (
                self.word(l - 1, wi + 1) << 63,
                self.word(l + 1, wi + 1) << 63,
            );
            let stop = (!b | (u & !((u >> 1) | nu)) | (d & !((d >> 1) | nd))) & mask;
            if stop != 0 {
                let x = wi * 64 + 63 - stop.leading_zeros() as usize;
                if let Some(g) = goal {
                    if g < pos && g >= x {
                        return Some(g);
                    }
                }
                return if (b >> (x % 64)) & 1 == 1 {
                    Some(x)
                } else {
                    None
                };
            }
            if wi == 0 {
                return None;
            }
            wi -= 1;
            mask = !0;
        }
    }
}

/// Straight jump from padded index `i` along (dr, dc), one of which is 0: the
/// next blocked cell ends it (None); a cell beside which a side cell opens up
/// behind a wall, or the goal, is a jump point.
#[inline]
fn jump_straight(map: &Padded, i: usize, dr: isize, dc: isize, goal: usize) -> Option<usize> {
    let w = map.w;
    let (r, c) = (i / w, i % w);
    if dr == 0 {
        let g = (goal / w == r).then_some(goal % w);
        let x = if dc > 0 {
            map.row_bits.scan_up(r, c, g)
        } else {
            map.row_bits.scan_down(r, c, g)
        }?;
        Some(r * w + x)
    } else {
        let g = (goal % w == c).then_some(goal / w);
        let x = if dr > 0 {
            map.col_bits.scan_up(c, r, g)
        } else {
            map.col_bits.scan_down(c, r, g)
        }?;
        Some(x * w + c)
    }
}

#[inline]
fn jump_diag(map: &Padded, mut i: usize, dr: isize, dc: isize, goal: usize) -> Option<usize> {
    let (free, w) = (&map.free[..], map.w);
    let vr = dr * w as isize;
    let d = vr + dc;
    loop {
        if !(free[step(i, dc)] && free[step(i, vr)] && free[step(i, d)]) {
            return None;
        }
        i = step(i, d);
        if i == goal
            || jump_straight(map, i, 0, dc, goal).is_some()
            || jump_straight(map, i, dr, 0, goal).is_some()
        {
            return Some(i);
        }
    }
}

#[inline]
fn octile_idx(w: usize, a: usize, b: usize) -> f64 {
    let dr = (a / w).abs_diff(b / w) as f64;
    let dc = (a % w).abs_diff(b % w) as f64;
    let (lo, hi) = if dr < dc { (dr, dc) } else { (dc, dr) };
    hi + (SQRT2 - 1.0) * lo
}

/// Search from `start` to `goal` (padded indices of free cells). Returns the jump
/// points from start to goal and the path cost in cells, or `None` when no path exists.
pub(crate) fn search(
    map: &Padded,
    s: &mut Scratch,
    start: usize,
    goal: usize,
) -> Option<(Vec<usize>, f64)> {
    let free = &map.free[..];
    let w = map.w;
    if !free.get(start).copied().unwrap_or(false) || !free.get(goal).copied().unwrap_or(false) {
        return None;
    }
    if s.g.len() != free.len() {
        *s = Scratch::new(free.len());
    }
    if start == goal {
        return Some((vec![start], 0.0));
    }
    s.next_gen();
    let (open, closed) = (2 * s.gen, 2 * s.gen + 1);
    s.g[start] = 0.0;
    s.parent[start] = start as u32;
    s.stamp[start] = open;
    s.heap.push(Reverse((
        octile_idx(w, start, goal).to_bits(),
        start as u32,
    )));
    let mut dirs: [(isize, isize); 8] = [(0, 0); 8];
    while let Some(Reverse((_, iu))) = s.heap.pop() {
        let i = iu as usize;
        if s.stamp[i] == closed {
            continue;
        }
        s.stamp[i] = closed;
        if i == goal {
            let mut pts = vec![goal];
            let mut k = goal;
            while k != start {
                k = s.parent[k] as usize;
                pts.push(k);
            }
            pts.reverse();
            return Some((pts, s.g[goal]));
        }
        // pruned successor directions
        let mut nd = 0;
        let par = s.parent[i] as usize;
        if par == i {
            for d in super::MOVES8 {
                dirs[nd] = d;
                nd += 1;
            }
        } else {
            let dr = ((i / w) as isize - (par / w) as isize).signum();
            let dc = ((i % w) as isize - (par % w) as isize).signum();
            if dr != 0 && dc != 0 {
                dirs[0] = (0, dc);
                dirs[1] = (dr, 0);
                dirs[2] = (dr, dc);
                nd = 3;
            } else if dr == 0 {
                dirs[0] = (0, dc);
                dirs[1] = (-1, dc);
                dirs[2] = (1, dc);
                nd = 3;
                if free[i - w] {
                    dirs[nd] = (-1, 0);
                    nd += 1;
                }
                if free[i + w] {
                    dirs[nd] = (1, 0);
                    nd += 1;
                }
            } else {
                dirs[0] = (dr, 0);
                dirs[1] = (dr, -1);
                dirs[2] = (dr, 1);
                nd = 3;
                if free[i - 1] {
                    dirs[nd] = (0, -1);
                    nd += 1;
                }
                if free[i + 1] {
                    dirs[nd] = (0, 1);
                    nd += 1;
                }
            }
        }
        let gi = s.g[i];
        for &(dr, dc) in &dirs[..nd] {
            let j = if dr != 0 && dc != 0 {
                jump_diag(map, i, dr, dc, goal)
            } else {
                jump_straight(map, i, dr, dc, goal)
            };
            let Some(j) = j else { continue };
            if s.stamp[j] == closed {
                continue;
            }
            let ng = gi + octile_idx(w, i, j);
            if s.stamp[j] != open || ng < s.g[j] {
                s.g[j] = ng;
                s.parent[j] = i as u32;
                s.stamp[j] = open;
                let f = ng + octile_idx(w, j, goal);
                s.heap.push(Reverse((f.to_bits(), j as u32)));
            }
        }
    }
    None
}

/// Expand jump points (joined by straight or diagonal runs) into every cell.
pub(crate) fn densify(w: usize, pts: &[usize]) -> Vec<usize> {
    let mut out = Vec::with_capacity(pts.len() * 8);
    let Some(&first) = pts.first() else {
        return out;
    };
    out.push(first);
    for win in pts.windows(2) {
        let (a, b) = (win[0], win[1]);
        let (ddr, ddc) = (
            (b / w) as isize - (a / w) as isize,
            (b % w) as isize - (a % w) as isize,
        );
        let d = ddr.signum() * w as isize + ddc.signum();
        let n = ddr.unsigned_abs().max(ddc.unsigned_abs());
        let mut i = a;
        for _ in 0..n {
            i = step(i, d);
            out.push(i);
        }
    }
    out
}
