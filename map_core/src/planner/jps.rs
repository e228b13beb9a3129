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

/// Straight jump from `i` along `d`; `p` is the perpendicular offset (w for a
/// horizontal move, 1 for a vertical one).
#[inline]
fn jump_straight(free: &[bool], mut i: usize, d: isize, p: usize, goal: usize) -> Option<usize> {
    loop {
        let back = i;
        i = step(i, d);
        if !free[i] {
            return None;
        }
        if i == goal {
            return Some(i);
        }
        if (free[i - p] && !free[back - p]) || (free[i + p] && !free[back + p]) {
            return Some(i);
        }
    }
}

#[inline]
fn jump_diag(
    free: &[bool],
    w: usize,
    mut i: usize,
    dr: isize,
    dc: isize,
    goal: usize,
) -> Option<usize> {
    let vr = dr * w as isize;
    let d = vr + dc;
    loop {
        if !(free[step(i, dc)] && free[step(i, vr)] && free[step(i, d)]) {
            return None;
        }
        i = step(i, d);
        if i == goal
            || jump_straight(free, i, dc, w, goal).is_some()
            || jump_straight(free, i, vr, 1, goal).is_some()
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
            for d in [
                (-1, 0),
                (1, 0),
                (0, -1),
                (0, 1),
                (-1, -1),
                (-1, 1),
                (1, -1),
                (1, 1),
            ] {
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
                jump_diag(free, w, i, dr, dc, goal)
            } else if dr == 0 {
                jump_straight(free, i, dc, w, goal)
            } else {
                jump_straight(free, i, dr * w as isize, 1, goal)
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
