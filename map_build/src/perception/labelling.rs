//! Eq. 2 of the paper: a category for each SAM mask from the pixel-label map.
//!
//! For one mask: keep the label-map cells inside the mask (region matching), count
//! each distinct label (`numpy.unique(labels[mask], return_counts=True)`: labels in
//! increasing order), score each label by `count / mask pixels` (a value in (0, 1]),
//! and sort the scores in descending order (ties: the smaller label first, as a
//! stable sort of `numpy.unique`'s output gives). The first `top_k` (label, score)
//! pairs are kept for inspection; the mask's category is the best-scoring label
//! among them that is not a background label.
//!
//! The paper sets the cells outside the mask to zero and runs `unique` on the whole
//! matrix; here the cells outside the mask are not counted at all, so label 0 keeps
//! its meaning ("other") instead of also counting the outside of the mask.
//!
//! A mask is dropped, with a [`DropReason`], when it has fewer than `min_area`
//! pixels, when no non-background label is among its top k, or when the best object
//! label scores below `min_score`. Masks are labelled independently; where masks
//! overlap, the map assembly decides which instance a cell belongs to.

use super::error::PerceptionError;
use super::mask::Mask;
use map_core::grid::Grid;

/// A per-cell category label map (the argmax of the pixel-text similarity) and the
/// category list it indexes: cell value `v` names `categories[v]`.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelMap {
    labels: Grid<u16>,
    categories: Vec<String>,
}

impl LabelMap {
    /// Check that every cell names a category (`v < categories.len()`).
    pub fn new(labels: Grid<u16>, categories: Vec<String>) -> Result<LabelMap, PerceptionError> {
        if categories.len() > usize::from(u16::MAX) + 1 {
            return Err(PerceptionError::TooManyCategories {
                what: "label map".into(),
                count: categories.len(),
            });
        }
        let n = categories.len();
        if let Some(i) = labels.as_slice().iter().position(|&v| usize::from(v) >= n) {
            return Err(PerceptionError::LabelOutOfRange {
                what: "label map".into(),
                cell: labels.cell_of(i),
                value: labels.as_slice()[i],
                categories: n,
            });
        }
        Ok(LabelMap { labels, categories })
    }

    /// Without the range check: callers guarantee every value indexes `categories`.
    pub(crate) fn new_trusted(labels: Grid<u16>, categories: Vec<String>) -> LabelMap {
        LabelMap { labels, categories }
    }

    /// The per-cell labels.
    pub fn labels(&self) -> &Grid<u16> {
        &self.labels
    }

    /// The category list: label `v` names `categories()[v]`.
    pub fn categories(&self) -> &[String] {
        &self.categories
    }

    /// The category a label names.
    pub fn name(&self, label: u16) -> Option<&str> {
        self.categories.get(usize::from(label)).map(String::as_str)
    }

    /// The label of a category name.
    pub fn label_of(&self, name: &str) -> Option<u16> {
        self.categories
            .iter()
            .position(|c| c == name)
            .and_then(|i| u16::try_from(i).ok())
    }

    /// The labels and the category list.
    pub fn into_parts(self) -> (Grid<u16>, Vec<String>) {
        (self.labels, self.categories)
    }
}

/// Thresholds of the Eq. 2 labelling.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelConfig {
    /// Labels that name no object (unlabelled, "other", floor): never a mask's
    /// category. Default: `[0]`.
    pub background: Vec<u16>,
    /// How many of the best-scoring labels are kept per mask and searched for the
    /// category. Default: 3.
    pub top_k: usize,
    /// Lowest score (fraction of the mask's pixels) of the category label. Default:
    /// 0.3, so a label must cover nearly a third of the mask.
    pub min_score: f64,
    /// Fewest pixels a mask (and, after overlaps are resolved, its visible part) must
    /// have. Default: 4 cells (0.01 m^2 at 0.05 m cells).
    pub min_area: u64,
}

impl Default for LabelConfig {
    fn default() -> Self {
        LabelConfig {
            background: vec![0],
            top_k: 3,
            min_score: 0.3,
            min_area: 4,
        }
    }
}

/// One label's share of a mask.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LabelScore {
    /// The label (an index into the category list).
    pub label: u16,
    /// Cells of the mask with this label.
    pub count: u64,
    /// `count / mask pixels`.
    pub score: f64,
}

/// A mask that got a category.
#[derive(Debug, Clone, PartialEq)]
pub struct MaskLabel {
    /// Index of the mask in the input list.
    pub mask: usize,
    /// Pixels of the mask.
    pub area: u64,
    /// The category label and its score.
    pub label: u16,
    /// Share of the mask's pixels with the category label, in (0, 1].
    pub score: f64,
    /// The best `top_k` labels, best first (background labels included).
    pub top_k: Vec<LabelScore>,
}

/// Why a mask yields no instance.
#[derive(Debug, Clone, PartialEq)]
pub enum DropReason {
    /// Fewer pixels than `min_area`.
    TooSmall {
        /// Pixels of the mask.
        area: u64,
        /// The configured `min_area`.
        min_area: u64,
    },
    /// Only background labels among the top k (`best` is the top one).
    NoObjectLabel {
        /// The top-scoring (background) label; `None` when there is no label at all.
        best: Option<LabelScore>,
    },
    /// The best object label scores below `min_score`.
    LowScore {
        /// The best-scoring object label.
        best: LabelScore,
        /// The configured `min_score`.
        min_score: f64,
    },
    /// Other (smaller) masks cover it, leaving fewer than `min_area` visible pixels.
    Covered {
        /// Pixels of the mask left visible.
        visible: u64,
        /// The configured `min_area`.
        min_area: u64,
    },
}

impl std::fmt::Display for DropReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DropReason::TooSmall { area, min_area } => {
                write!(f, "too small: {area} pixels, fewer than {min_area}")
            }
            DropReason::NoObjectLabel { best: Some(b) } => write!(
                f,
                "no object label: background label {} covers {:.3} of it",
                b.label, b.score
            ),
            DropReason::NoObjectLabel { best: None } => write!(f, "no label at all"),
            DropReason::LowScore { best, min_score } => write!(
                f,
                "low score: best object label {} covers {:.3}, below {min_score}",
                best.label, best.score
            ),
            DropReason::Covered { visible, min_area } => write!(
                f,
                "covered by smaller masks: {visible} pixels visible, fewer than {min_area}"
            ),
        }
    }
}

/// A mask that yields no instance, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct DroppedMask {
    /// Index of the mask in the input list.
    pub mask: usize,
    /// Why it was dropped.
    pub reason: DropReason,
}

/// Eq. 2 over all masks: the labelled ones and the dropped ones, each in mask order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Labelling {
    /// The masks that got a category.
    pub kept: Vec<MaskLabel>,
    /// The masks that yield no instance.
    pub dropped: Vec<DroppedMask>,
}

/// Label counts over the cells of a mask, reused across masks: four counters per
/// possible `u16` label (so no label can index out of range), one per lane of
/// four consecutive cells. Label maps are mostly long runs of one label, and one
/// counter per label would make every increment wait for the previous one to be
/// stored (about 5 ns a cell, measured in `bench/eq2_compare.sh`); four lanes
/// break that chain.
#[derive(Debug)]
pub(crate) struct LabelCounter {
    counts: Box<[[u32; 4]]>,
}

impl LabelCounter {
    pub(crate) fn new() -> Self {
        LabelCounter {
            counts: vec![[0u32; 4]; usize::from(u16::MAX) + 1].into_boxed_slice(),
        }
    }

    /// `numpy.unique(labels[mask], return_counts=True)`: (label, count) in increasing
    /// label order. `n_labels` bounds the labels present (all `< n_labels`).
    pub(crate) fn unique_counts(
        &mut self,
        labels: &[u16],
        mask: &Mask,
        n_labels: usize,
    ) -> Vec<(u16, u64)> {
        let counts = &mut self.counts;
        let mut bump = |v: u16, lane: usize| {
            if let Some(c) = counts.get_mut(usize::from(v)) {
                c[lane] += 1;
            }
        };
        for &(s, e) in mask.runs() {
            let Some(row) = labels.get(s..e) else {
                continue;
            };
            let mut quads = row.chunks_exact(4);
            for q in &mut quads {
                bump(q[0], 0);
                bump(q[1], 1);
                bump(q[2], 2);
                bump(q[3], 3);
            }
            for &v in quads.remainder() {
                bump(v, 0);
            }
        }
        let mut out = Vec::new();
        for (v, c) in counts.iter_mut().enumerate().take(n_labels) {
            let total: u64 = c.iter().map(|&x| u64::from(x)).sum();
            if total > 0 {
                out.push((v as u16, total));
                *c = [0; 4];
            }
        }
        out
    }
}

/// Eq. 2 scores of `(label, count)` pairs over a mask of `area` pixels, best first
/// (ties: smaller label first).
pub fn eq2_scores(counts: &[(u16, u64)], area: u64) -> Vec<LabelScore> {
    let mut v: Vec<LabelScore> = counts
        .iter()
        .map(|&(label, count)| LabelScore {
            label,
            count,
            score: if area == 0 {
                0.0
            } else {
                count as f64 / area as f64
            },
        })
        .collect();
    v.sort_by(|a, b| b.count.cmp(&a.count).then(a.label.cmp(&b.label)));
    v
}

/// `numpy.unique(labels[mask], return_counts=True)` for one mask: (label, count) in
/// increasing label order. Errors when the mask's size differs from the label map's.
pub fn unique_labels(map: &LabelMap, mask: &Mask) -> Result<Vec<(u16, u64)>, PerceptionError> {
    check_shape(map.labels(), mask, 0)?;
    Ok(LabelCounter::new().unique_counts(map.labels.as_slice(), mask, map.categories.len()))
}

fn check_shape(labels: &Grid<u16>, mask: &Mask, index: usize) -> Result<(), PerceptionError> {
    if (mask.rows(), mask.cols()) != (labels.rows(), labels.cols()) {
        return Err(PerceptionError::Shape {
            what: format!("mask {index}"),
            rows: mask.rows(),
            cols: mask.cols(),
            frame_rows: labels.rows(),
            frame_cols: labels.cols(),
        });
    }
    Ok(())
}

/// Decide one mask from its Eq. 2 scores.
fn decide(
    index: usize,
    area: u64,
    scores: Vec<LabelScore>,
    cfg: &LabelConfig,
) -> Result<MaskLabel, DropReason> {
    if area < cfg.min_area || area == 0 {
        return Err(DropReason::TooSmall {
            area,
            min_area: cfg.min_area,
        });
    }
    let mut top = scores;
    top.truncate(cfg.top_k.max(1));
    let Some(best) = top
        .iter()
        .find(|s| !cfg.background.contains(&s.label))
        .copied()
    else {
        return Err(DropReason::NoObjectLabel {
            best: top.first().copied(),
        });
    };
    if best.score < cfg.min_score {
        return Err(DropReason::LowScore {
            best,
            min_score: cfg.min_score,
        });
    }
    Ok(MaskLabel {
        mask: index,
        area,
        label: best.label,
        score: best.score,
        top_k: top,
    })
}

/// Eq. 2 for every mask. Errors only when a mask's size differs from the label
/// map's; masks without a confident label are returned in `dropped`.
pub fn label_masks(
    map: &LabelMap,
    masks: &[Mask],
    cfg: &LabelConfig,
) -> Result<Labelling, PerceptionError> {
    for (i, m) in masks.iter().enumerate() {
        check_shape(map.labels(), m, i)?;
    }
    let mut counter = LabelCounter::new();
    let labels = map.labels.as_slice();
    let n = map.categories.len();
    let mut out = Labelling::default();
    for (i, m) in masks.iter().enumerate() {
        let area = m.area();
        let decided = if area < cfg.min_area || area == 0 {
            decide(i, area, Vec::new(), cfg)
        } else {
            let counts = counter.unique_counts(labels, m, n);
            decide(i, area, eq2_scores(&counts, area), cfg)
        };
        match decided {
            Ok(l) => out.kept.push(l),
            Err(reason) => out.dropped.push(DroppedMask { mask: i, reason }),
        }
    }
    Ok(out)
}

/// The most frequent label of a mask's cells and its share (`None` for an empty
/// mask). Used for the colour layer when a per-cell colour label map is given.
pub(crate) fn mode_label(
    counter: &mut LabelCounter,
    labels: &Grid<u16>,
    mask: &Mask,
    n_labels: usize,
) -> Option<LabelScore> {
    let counts = counter.unique_counts(labels.as_slice(), mask, n_labels);
    eq2_scores(&counts, mask.area()).into_iter().next()
}
