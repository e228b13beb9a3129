//! SAM automatic-mask-generator output: a JSON list of objects with the fields of
//! the paper's Listing 1 (`segmentation`, `area`, `bbox` [x, y, w, h],
//! `predicted_iou`, `point_coords`, `stability_score`, `crop_box`).
//!
//! `segmentation` may be COCO RLE with compressed counts (`{"size": [h, w],
//! "counts": "<string>"}`, what `SamAutomaticMaskGenerator(output_mode="coco_rle")`
//! writes), COCO RLE with uncompressed counts (`"counts": [ints]`), or a 2-D array of
//! booleans or 0/1 (rows of the `binary_mask` output, `mask.tolist()`). Other fields
//! (the paper's `label`, `color`, ...) are ignored; `area`, where given, must equal
//! the decoded pixel count. All masks of a file must have the same size.

use std::io::Write;
use std::path::Path;

use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Serialize};

use super::error::{MaskLocation, PerceptionError};
use super::mask::{Mask, Rle, MAX_MASK_CELLS};
use map_core::grid::Grid;

/// One mask of SAM's output: the decoded segmentation and SAM's metadata.
#[derive(Debug, Clone, PartialEq)]
pub struct SamMask {
    /// The decoded mask.
    pub segmentation: Mask,
    /// Bounding box as SAM writes it: `[x0, y0, x1 - x0, y1 - y0]` with `x1`, `y1` the
    /// last set column and row (inclusive), so one less than the extent.
    pub bbox: Option<[f64; 4]>,
    /// SAM's predicted IoU of the mask, where given.
    pub predicted_iou: Option<f64>,
    /// The `[x, y]` prompt points SAM generated the mask from, where given.
    pub point_coords: Option<Vec<[f64; 2]>>,
    /// SAM's stability score of the mask, where given.
    pub stability_score: Option<f64>,
    /// The image crop SAM generated the mask in, `[x, y, w, h]`, where given.
    pub crop_box: Option<[f64; 4]>,
}

impl SamMask {
    /// A mask with SAM's bbox computed from it and no scores.
    pub fn from_mask(mask: Mask) -> SamMask {
        SamMask {
            bbox: sam_bbox(&mask),
            segmentation: mask,
            predicted_iou: None,
            point_coords: None,
            stability_score: None,
            crop_box: None,
        }
    }
}

/// SAM's bbox of a mask (`None` when empty).
fn sam_bbox(mask: &Mask) -> Option<[f64; 4]> {
    mask.bbox().map(|[x, y, w, h]| {
        [
            f64::from(x),
            f64::from(y),
            f64::from(w) - 1.0,
            f64::from(h) - 1.0,
        ]
    })
}

/// How [`write_sam_masks`] writes `segmentation`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SegmentationForm {
    /// COCO RLE with pycocotools' compressed counts string (SAM's `coco_rle`).
    #[default]
    CompressedRle,
    /// COCO RLE with the counts as a list of integers.
    Rle,
    /// Rows of booleans (SAM's `binary_mask`, as `tolist()` writes it).
    Bitmap,
}

/// Read a SAM masks JSON file.
pub fn read_sam_masks(path: impl AsRef<Path>) -> Result<Vec<SamMask>, PerceptionError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|source| PerceptionError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    sam_masks_from_str(&text, path)
}

/// Parse SAM masks JSON; `source` names it in errors.
pub fn sam_masks_from_str(
    text: &str,
    source: impl AsRef<Path>,
) -> Result<Vec<SamMask>, PerceptionError> {
    let path = source.as_ref();
    let de = &mut serde_json::Deserializer::from_str(text);
    let raw: Vec<RawMask> = serde_path_to_error::deserialize(de).map_err(|e| {
        let (mask, field) = split_path(e.path());
        let inner = e.into_inner();
        PerceptionError::Masks {
            path: path.to_path_buf(),
            at: MaskLocation {
                line: Some(inner.line()),
                column: Some(inner.column()),
                mask,
                field,
            },
            message: strip_position(&inner.to_string()),
        }
    })?;
    let mut out: Vec<SamMask> = Vec::with_capacity(raw.len());
    for (i, r) in raw.into_iter().enumerate() {
        let err = |field: &str, message: String| PerceptionError::Masks {
            path: path.to_path_buf(),
            at: MaskLocation {
                line: None,
                column: None,
                mask: Some(i),
                field: field.to_string(),
            },
            message,
        };
        let mask = match r.segmentation {
            RawSegmentation::Rle { size, counts } => {
                let rle = match counts {
                    RawCounts::Compressed(s) => Rle::from_compressed(size, &s)
                        .map_err(|e| err("segmentation.counts", e.to_string()))?,
                    RawCounts::Runs(counts) => Rle { size, counts },
                };
                Mask::from_rle(&rle).map_err(|e| {
                    let field = match e {
                        super::mask::RleError::TooLarge { .. } => "segmentation.size",
                        _ => "segmentation.counts",
                    };
                    err(field, e.to_string())
                })?
            }
            RawSegmentation::Bitmap(rows) => {
                let h = rows.len();
                let w = rows.first().map_or(0, Vec::len);
                if (h as u64) * (w as u64) > MAX_MASK_CELLS {
                    return Err(err(
                        "segmentation",
                        format!("{h}x{w} exceeds {MAX_MASK_CELLS} cells"),
                    ));
                }
                let mut data = Vec::with_capacity(h * w);
                for (r, row) in rows.into_iter().enumerate() {
                    if row.len() != w {
                        return Err(err(
                            &format!("segmentation[{r}]"),
                            format!("row {r} has {} values, row 0 has {w}", row.len()),
                        ));
                    }
                    data.extend(row.into_iter().map(|b| b.0));
                }
                match Grid::from_vec(h, w, data) {
                    Some(g) => Mask::from_grid(&g),
                    None => return Err(err("segmentation", "inconsistent size".into())),
                }
            }
        };
        if let Some(first) = out.first() {
            let (fr, fc) = (first.segmentation.rows(), first.segmentation.cols());
            if (mask.rows(), mask.cols()) != (fr, fc) {
                return Err(err(
                    "segmentation.size",
                    format!(
                        "mask is {}x{}, but mask 0 is {fr}x{fc}",
                        mask.rows(),
                        mask.cols()
                    ),
                ));
            }
        }
        if let Some(a) = r.area {
            if a != mask.area() {
                return Err(err(
                    "area",
                    format!(
                        "area {a} differs from the segmentation's {} pixels",
                        mask.area()
                    ),
                ));
            }
        }
        out.push(SamMask {
            segmentation: mask,
            bbox: r.bbox,
            predicted_iou: r.predicted_iou,
            point_coords: r.point_coords,
            stability_score: r.stability_score,
            crop_box: r.crop_box,
        });
    }
    Ok(out)
}

/// Write masks as SAM JSON (`area` from the segmentation; `bbox` as stored, else
/// computed in SAM's convention).
pub fn write_sam_masks(
    path: impl AsRef<Path>,
    masks: &[SamMask],
    form: SegmentationForm,
) -> Result<(), PerceptionError> {
    let path = path.as_ref();
    let io = |source| PerceptionError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::create(path).map_err(io)?;
    let mut w = std::io::BufWriter::new(file);
    write_sam_masks_to(&mut w, masks, form).map_err(io)?;
    w.flush().map_err(io)
}

/// Write masks as SAM JSON to any writer.
pub fn write_sam_masks_to(
    mut writer: impl Write,
    masks: &[SamMask],
    form: SegmentationForm,
) -> std::io::Result<()> {
    writer.write_all(b"[")?;
    for (i, m) in masks.iter().enumerate() {
        if i > 0 {
            writer.write_all(b",\n")?;
        }
        let seg = &m.segmentation;
        let segmentation = match form {
            SegmentationForm::CompressedRle | SegmentationForm::Rle => {
                let rle = seg.to_rle();
                let counts = if form == SegmentationForm::Rle {
                    OutCounts::Runs(rle.counts)
                } else {
                    OutCounts::Compressed(rle.to_compressed())
                };
                OutSegmentation::Rle {
                    size: rle.size,
                    counts,
                }
            }
            SegmentationForm::Bitmap => {
                let g = seg.to_grid();
                let cols = g.cols().max(1);
                OutSegmentation::Bitmap(g.as_slice().chunks(cols).map(<[bool]>::to_vec).collect())
            }
        };
        let record = OutMask {
            segmentation,
            area: seg.area(),
            bbox: m.bbox.or_else(|| sam_bbox(seg)),
            predicted_iou: m.predicted_iou,
            point_coords: m.point_coords.as_deref(),
            stability_score: m.stability_score,
            crop_box: m.crop_box,
        };
        serde_json::to_writer(&mut writer, &record).map_err(std::io::Error::other)?;
    }
    writer.write_all(b"]\n")
}

/// `[3].segmentation.counts` -> (Some(3), "segmentation.counts").
fn split_path(path: &serde_path_to_error::Path) -> (Option<usize>, String) {
    use serde_path_to_error::Segment;
    let mut segs = path.iter();
    let mask = match segs.next() {
        Some(Segment::Seq { index }) => Some(*index),
        _ => return (None, String::new()),
    };
    let mut field = String::new();
    for s in segs {
        match s {
            Segment::Seq { index } => field.push_str(&format!("[{index}]")),
            Segment::Map { key } => {
                if !field.is_empty() {
                    field.push('.');
                }
                field.push_str(key);
            }
            Segment::Enum { variant } => {
                if !field.is_empty() {
                    field.push('.');
                }
                field.push_str(variant);
            }
            Segment::Unknown => field.push_str(".?"),
        }
    }
    (mask, field)
}

/// serde_json appends " at line L column C"; the location is reported separately.
fn strip_position(msg: &str) -> String {
    match msg.rfind(" at line ") {
        Some(i) => msg[..i].to_string(),
        None => msg.to_string(),
    }
}

#[derive(Deserialize)]
struct RawMask {
    segmentation: RawSegmentation,
    #[serde(default)]
    area: Option<u64>,
    #[serde(default)]
    bbox: Option<[f64; 4]>,
    #[serde(default)]
    predicted_iou: Option<f64>,
    #[serde(default)]
    point_coords: Option<Vec<[f64; 2]>>,
    #[serde(default)]
    stability_score: Option<f64>,
    #[serde(default)]
    crop_box: Option<[f64; 4]>,
}

enum RawSegmentation {
    Rle { size: [usize; 2], counts: RawCounts },
    Bitmap(Vec<Vec<Bit>>),
}

impl<'de> Deserialize<'de> for RawSegmentation {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(SegmentationVisitor)
    }
}

struct SegmentationVisitor;

impl<'de> Visitor<'de> for SegmentationVisitor {
    type Value = RawSegmentation;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("COCO RLE ({\"size\": [h, w], \"counts\": ...}) or a 2-D array of booleans")
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct RawRle {
            size: [usize; 2],
            counts: RawCounts,
        }
        let r = RawRle::deserialize(de::value::MapAccessDeserializer::new(map))?;
        Ok(RawSegmentation::Rle {
            size: r.size,
            counts: r.counts,
        })
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        let mut rows = Vec::new();
        while let Some(row) = seq.next_element::<Vec<Bit>>()? {
            rows.push(row);
        }
        Ok(RawSegmentation::Bitmap(rows))
    }
}

enum RawCounts {
    Compressed(String),
    Runs(Vec<u64>),
}

impl<'de> Deserialize<'de> for RawCounts {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawCounts;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a compressed RLE string or a list of non-negative run lengths")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<RawCounts, E> {
                Ok(RawCounts::Compressed(v.to_string()))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<RawCounts, A::Error> {
                let mut v = Vec::new();
                while let Some(n) = seq.next_element::<u64>()? {
                    v.push(n);
                }
                Ok(RawCounts::Runs(v))
            }
        }
        d.deserialize_any(V)
    }
}

/// A boolean written as `true`/`false` or `1`/`0`.
struct Bit(bool);

impl<'de> Deserialize<'de> for Bit {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Bit;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("true, false, 0 or 1")
            }
            fn visit_bool<E: de::Error>(self, v: bool) -> Result<Bit, E> {
                Ok(Bit(v))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Bit, E> {
                match v {
                    0 | 1 => Ok(Bit(v == 1)),
                    _ => Err(E::invalid_value(de::Unexpected::Unsigned(v), &self)),
                }
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Bit, E> {
                match v {
                    0 | 1 => Ok(Bit(v == 1)),
                    _ => Err(E::invalid_value(de::Unexpected::Signed(v), &self)),
                }
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Serialize)]
struct OutMask<'a> {
    segmentation: OutSegmentation,
    area: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    bbox: Option<[f64; 4]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    predicted_iou: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    point_coords: Option<&'a [[f64; 2]]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    stability_score: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    crop_box: Option<[f64; 4]>,
}

#[derive(Serialize)]
#[serde(untagged)]
enum OutSegmentation {
    Rle { size: [usize; 2], counts: OutCounts },
    Bitmap(Vec<Vec<bool>>),
}

#[derive(Serialize)]
#[serde(untagged)]
enum OutCounts {
    Compressed(String),
    Runs(Vec<u64>),
}
