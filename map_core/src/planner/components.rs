//! Connected free areas. Moves never cut corners, so a diagonal step needs both
//! orthogonal neighbours free: 4-connected areas are exactly the reachable sets.

use super::Padded;

/// Label each free cell of `map` (padded index) with its area number (1, 2, ...);
/// blocked cells get 0.
pub(crate) fn label(map: &Padded) -> Vec<u32> {
    let n = map.free.len();
    let w = map.w;
    let mut labels = vec![0u32; n];
    let mut stack: Vec<usize> = Vec::new();
    let mut next = 0u32;
    for seed in 0..n {
        if !map.free[seed] || labels[seed] != 0 {
            continue;
        }
        next += 1;
        labels[seed] = next;
        stack.push(seed);
        while let Some(i) = stack.pop() {
            // the blocked border keeps i +- 1 and i +- w inside the array for free cells
            for j in [i - 1, i + 1, i - w, i + w] {
                if map.free[j] && labels[j] == 0 {
                    labels[j] = next;
                    stack.push(j);
                }
            }
        }
    }
    labels
}
