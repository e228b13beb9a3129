//! SAM output files: the three segmentation forms decode to the same masks, our
//! COCO RLE encoder reproduces pycocotools' strings byte for byte (fixtures written
//! by `perception_data/make_sam_fixtures.py`), files round-trip, and bad files are
//! errors naming the file, the mask and the field.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::PathBuf;

use map_build::perception::{
    read_sam_masks, sam_masks_from_str, write_sam_masks, Mask, PerceptionError, Rle, SamMask,
    SegmentationForm,
};
use map_core::{Cell, Grid};
use proptest::prelude::*;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/perception_data")
        .join(name)
}

fn raw_records(name: &str) -> Vec<serde_json::Value> {
    serde_json::from_str(&std::fs::read_to_string(data(name)).unwrap()).unwrap()
}

#[test]
fn three_forms_decode_to_the_same_masks() {
    let coco = read_sam_masks(data("sam_coco.json")).unwrap();
    let unc = read_sam_masks(data("sam_uncompressed.json")).unwrap();
    let bits = read_sam_masks(data("sam_bitmap.json")).unwrap();
    assert_eq!(coco.len(), 9);
    assert_eq!(coco, unc);
    assert_eq!(coco, bits);
    let raw = raw_records("sam_bitmap.json");
    for (i, (m, r)) in coco.iter().zip(&raw).enumerate() {
        let seg = &m.segmentation;
        assert_eq!((seg.rows(), seg.cols()), (61, 83), "mask {i}");
        // cell-by-cell against the boolean rows in the file
        let rows = r["segmentation"].as_array().unwrap();
        for (y, row) in rows.iter().enumerate() {
            for (x, v) in row.as_array().unwrap().iter().enumerate() {
                assert_eq!(
                    seg.contains(Cell::new(y, x)),
                    v.as_bool().unwrap(),
                    "mask {i} ({y}, {x})"
                );
            }
        }
        assert_eq!(seg.area(), r["area"].as_u64().unwrap());
        let bbox: Vec<f64> = r["bbox"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(m.bbox.unwrap().to_vec(), bbox);
        if seg.area() > 0 {
            // SAM's bbox is one less than the extent; ours is the extent
            assert_eq!(
                SamMask::from_mask(seg.clone()).bbox,
                Some([bbox[0], bbox[1], bbox[2], bbox[3]])
            );
            let [x, y, w, h] = seg.bbox().unwrap();
            assert_eq!([x, y, w - 1, h - 1].map(f64::from).to_vec(), bbox);
        }
        assert!(m.predicted_iou.is_some() && m.stability_score.is_some());
        assert_eq!(m.crop_box, Some([0.0, 0.0, 83.0, 61.0]));
    }
    // the first pixel only, the full mask, the empty one
    assert_eq!(
        coco[1].segmentation.cells().collect::<Vec<_>>(),
        [Cell::new(0, 0)]
    );
    assert_eq!(coco[3].segmentation.area(), 61 * 83);
    assert!(coco[0].segmentation.is_empty());
}

#[test]
fn encoder_reproduces_pycocotools_strings_and_counts() {
    let masks = read_sam_masks(data("sam_bitmap.json")).unwrap();
    let coco = raw_records("sam_coco.json");
    let unc = raw_records("sam_uncompressed.json");
    for (i, m) in masks.iter().enumerate() {
        let rle = m.segmentation.to_rle();
        assert_eq!(rle.size, [61, 83]);
        let want: Vec<u64> = unc[i]["segmentation"]["counts"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap())
            .collect();
        assert_eq!(rle.counts, want, "mask {i}");
        let s = coco[i]["segmentation"]["counts"].as_str().unwrap();
        assert_eq!(rle.to_compressed(), s, "mask {i}");
        assert_eq!(Rle::from_compressed([61, 83], s).unwrap(), rle);
    }
}

#[test]
fn files_round_trip_in_every_form() {
    let masks = read_sam_masks(data("sam_coco.json")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for form in [
        SegmentationForm::CompressedRle,
        SegmentationForm::Rle,
        SegmentationForm::Bitmap,
    ] {
        let p = dir.path().join(format!("{form:?}.json"));
        write_sam_masks(&p, &masks, form).unwrap();
        assert_eq!(read_sam_masks(&p).unwrap(), masks, "{form:?}");
    }
    // without metadata: area and SAM's bbox are written from the mask
    let bare: Vec<SamMask> = masks
        .iter()
        .map(|m| SamMask {
            bbox: None,
            ..SamMask::from_mask(m.segmentation.clone())
        })
        .collect();
    let p = dir.path().join("bare.json");
    write_sam_masks(&p, &bare, SegmentationForm::CompressedRle).unwrap();
    let back = read_sam_masks(&p).unwrap();
    assert_eq!(
        back[4].bbox,
        SamMask::from_mask(masks[4].segmentation.clone()).bbox
    );
    assert_eq!(back[4].bbox, masks[4].bbox);
}

#[test]
fn bitmaps_may_be_written_as_zeros_and_ones() {
    let m = sam_masks_from_str(r#"[{"segmentation": [[0, 1, 1], [1, 0, 0]]}]"#, "m.json").unwrap();
    let g = m[0].segmentation.to_grid();
    assert_eq!(
        g,
        Grid::from_vec(2, 3, vec![false, true, true, true, false, false]).unwrap()
    );
    // column-major: col 0 = [0, 1], col 1 = [1, 0], col 2 = [1, 0]
    assert_eq!(m[0].segmentation.to_rle().counts, vec![1, 2, 1, 1, 1]);
    assert!(sam_masks_from_str("[]", "m.json").unwrap().is_empty());
}

fn err(text: &str) -> String {
    let e = sam_masks_from_str(text, "masks.json").unwrap_err();
    assert!(matches!(e, PerceptionError::Masks { .. }), "{e:?}");
    e.to_string()
}

#[test]
fn errors_name_the_file_the_mask_and_the_field() {
    let ok = r#"{"segmentation": {"size": [2, 2], "counts": "04"}}"#;

    // a character outside COCO's alphabet, in the second mask
    let e = err(&format!(
        r#"[{ok}, {{"segmentation": {{"size": [2, 2], "counts": "0 4"}}}}]"#
    ));
    assert!(
        e.starts_with("masks.json: mask 1: field `segmentation.counts`: character ' ' at offset 1"),
        "{e}"
    );

    // counts that do not cover h x w
    let e = err(r#"[{"segmentation": {"size": [2, 3], "counts": [1, 2]}}]"#);
    assert!(
        e.contains(
            "mask 0: field `segmentation.counts`: the counts add up to 3, but size h x w is 6"
        ),
        "{e}"
    );

    // a JSON type error: line and column, mask and field from the parser
    let e = err(&format!("[{ok},\n {ok},\n {{\"segmentation\": {{\"size\": [2, 2], \"counts\": \"04\"}}, \"bbox\": \"wide\"}}]"));
    assert!(e.starts_with("masks.json:3:"), "{e}");
    assert!(
        e.contains(": mask 2: field `bbox`: invalid type: string \"wide\""),
        "{e}"
    );

    // a negative run length
    let e = err(r#"[{"segmentation": {"size": [2, 2], "counts": [1, -3]}}]"#);
    assert!(e.contains("mask 0: field `segmentation.counts[1]`"), "{e}");

    // a bitmap value that is not a boolean
    let e = err(r#"[{"segmentation": [[0, 1], [2, 0]]}]"#);
    assert!(e.contains("mask 0: field `segmentation[1][0]`"), "{e}");
    assert!(e.contains("expected true, false, 0 or 1"), "{e}");

    // ragged rows
    let e = err(r#"[{"segmentation": [[0, 1], [1]]}]"#);
    assert!(
        e.contains("mask 0: field `segmentation[1]`: row 1 has 1 values, row 0 has 2"),
        "{e}"
    );

    // masks of different sizes in one file
    let e = err(&format!(
        r#"[{ok}, {{"segmentation": {{"size": [3, 2], "counts": [6]}}}}]"#
    ));
    assert!(
        e.contains("mask 1: field `segmentation.size`: mask is 3x2, but mask 0 is 2x2"),
        "{e}"
    );

    // area that disagrees with the segmentation
    let e = err(r#"[{"segmentation": {"size": [2, 2], "counts": [1, 2, 1]}, "area": 3}]"#);
    assert!(
        e.contains("mask 0: field `area`: area 3 differs from the segmentation's 2 pixels"),
        "{e}"
    );

    // a size too large to allocate
    let e = err(r#"[{"segmentation": {"size": [100000, 100000], "counts": [1]}}]"#);
    assert!(e.contains("mask 0: field `segmentation.size`"), "{e}");

    // missing segmentation, unknown RLE key, not a list
    let e = err(r#"[{"area": 3}]"#);
    assert!(
        e.contains("mask 0") && e.contains("missing field `segmentation`"),
        "{e}"
    );
    let e = err(r#"[{"segmentation": {"size": [1, 1], "counts": [1], "cnts": 1}}]"#);
    assert!(e.contains("unknown field `cnts`"), "{e}");
    let e = err(r#"{"segmentation": []}"#);
    assert!(e.contains("expected a sequence"), "{e}");
}

#[test]
fn missing_file_is_an_io_error_naming_it() {
    let e = read_sam_masks("/nonexistent/masks.json").unwrap_err();
    assert!(matches!(e, PerceptionError::Io { .. }));
    assert!(
        e.to_string().starts_with("/nonexistent/masks.json: "),
        "{e}"
    );
}

proptest! {
    #[test]
    fn random_masks_round_trip_through_compressed_rle(
        rows in 1usize..12,
        cols in 1usize..12,
        seed in any::<u64>(),
        density in 0.0f64..1.0,
    ) {
        // a cheap deterministic generator from the seed
        let mut s = seed | 1;
        let data: Vec<bool> = (0..rows * cols)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s % 1000) as f64 / 1000.0 < density
            })
            .collect();
        let g = Grid::from_vec(rows, cols, data).unwrap();
        let m = Mask::from_grid(&g);
        prop_assert_eq!(m.to_grid(), g.clone());
        prop_assert_eq!(m.area(), g.as_slice().iter().filter(|&&b| b).count() as u64);
        let rle = m.to_rle();
        prop_assert_eq!(rle.counts.iter().sum::<u64>(), (rows * cols) as u64);
        prop_assert!(rle.counts.iter().skip(1).all(|&c| c > 0), "{:?}", rle.counts);
        let back = Rle::from_compressed(rle.size, &rle.to_compressed()).unwrap();
        prop_assert_eq!(&back, &rle);
        prop_assert_eq!(Mask::from_rle(&back).unwrap(), m.clone());
        let cells: Vec<Cell> = m.cells().collect();
        prop_assert_eq!(Mask::from_cells(rows, cols, cells), m);
    }
}
