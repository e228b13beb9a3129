//! Rendering example scenes: image size, instance colours at their centres, the
//! path, stops, the final pose and the PNG file.

// Test helpers outside #[test] functions may unwrap and panic too.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::PathBuf;

use map_core::render::{
    auto_scale, colour_rgb, render_png, render_rgb, RenderOptions, RenderOverlay, PATH_RGB,
    STOP_RGB, UNKNOWN_RGB, WALL_RGB,
};
use map_core::{IvlMap, Point, Pose, Scene};

fn map(name: &str) -> IvlMap {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../examples/scenes")
        .join(name);
    IvlMap::from_scene(&Scene::from_path(p).unwrap())
}

fn pixel_at(img: &image::RgbImage, map: &IvlMap, s: u32, p: Point) -> [u8; 3] {
    let c = map.frame.cell_at(p).unwrap();
    // the middle pixel of the cell
    img.get_pixel(c.col as u32 * s + s / 2, c.row as u32 * s + s / 2)
        .0
}

#[test]
fn default_scale_gives_800_to_1200_px_and_cells_of_that_size() {
    for name in [
        "flat-a.scene.json",
        "office-b.scene.json",
        "house-c.scene.json",
    ] {
        let m = map(name);
        let s = auto_scale(m.frame.cols);
        let img = render_rgb(&m, &RenderOverlay::default(), &RenderOptions::default());
        assert_eq!(img.width(), m.frame.cols as u32 * s, "{name}");
        assert_eq!(img.height(), m.frame.rows as u32 * s, "{name}");
        assert!(
            (800..=1200).contains(&img.width()),
            "{name}: {} px",
            img.width()
        );
    }
    let m = map("flat-a.scene.json");
    let opts = RenderOptions {
        scale: Some(2),
        ..RenderOptions::default()
    };
    let img = render_rgb(&m, &RenderOverlay::default(), &opts);
    assert_eq!((img.width(), img.height()), (480, 360));
}

#[test]
fn instances_are_filled_with_their_colour_and_walls_are_dark() {
    let m = map("flat-a.scene.json");
    let opts = RenderOptions {
        ids: false,
        regions: false,
        start_pose: false,
        ..RenderOptions::default()
    };
    let s = auto_scale(m.frame.cols);
    let img = render_rgb(&m, &RenderOverlay::default(), &opts);
    for inst in &m.instances {
        let want = inst
            .colour
            .as_deref()
            .and_then(colour_rgb)
            .unwrap_or(UNKNOWN_RGB);
        assert_eq!(
            pixel_at(&img, &m, s, inst.center()),
            want,
            "instance {} ({} {:?})",
            inst.id,
            inst.label,
            inst.colour
        );
    }
    // red sofa, yellow table, the outer south wall, a free floor cell
    let sofa = m.instance_by_id(1).unwrap();
    assert_eq!(sofa.colour.as_deref(), Some("red"));
    assert_eq!(pixel_at(&img, &m, s, sofa.center()), [214, 39, 40]);
    assert_eq!(pixel_at(&img, &m, s, Point::new(3.0, 0.1)), WALL_RGB);
    assert_eq!(pixel_at(&img, &m, s, Point::new(4.0, 3.5)), [255, 255, 255]);
}

#[test]
fn ids_are_drawn_at_footprint_centres() {
    let m = map("flat-a.scene.json");
    let s = auto_scale(m.frame.cols);
    let plain = RenderOptions {
        ids: false,
        ..RenderOptions::default()
    };
    let a = render_rgb(&m, &RenderOverlay::default(), &plain);
    let b = render_rgb(&m, &RenderOverlay::default(), &RenderOptions::default());
    for inst in &m.instances {
        let c = m.frame.cell_at(inst.center()).unwrap();
        let (x, y) = (c.col as u32 * s, c.row as u32 * s);
        // the label box (white, black glyph pixels) replaces the fill near the centre
        let changed = (x.saturating_sub(6)..x + 6)
            .flat_map(|px| (y.saturating_sub(6)..y + 6).map(move |py| (px, py)))
            .any(|(px, py)| a.get_pixel(px, py) != b.get_pixel(px, py));
        assert!(changed, "no label drawn for instance {}", inst.id);
    }
}

#[test]
fn path_stops_and_final_pose_are_drawn() {
    let m = map("flat-a.scene.json");
    let s = auto_scale(m.frame.cols);
    // from the living room through the dining-room door to the kitchen table
    let path = [
        Point::new(4.0, 3.0),
        Point::new(6.0, 2.7),
        Point::new(7.2, 2.7),
        Point::new(7.2, 4.3),
        Point::new(9.4, 4.5),
    ];
    let stops = [
        (Pose::new(7.2, 2.7, 90.0), "move_to_object".to_string()),
        (Pose::new(9.4, 4.5, 90.0), "move_to_region".to_string()),
    ];
    let overlay = RenderOverlay {
        path: &path,
        stops: &stops,
        final_pose: Some(Pose::new(9.4, 4.5, 90.0)),
    };
    let img = render_rgb(&m, &overlay, &RenderOptions::default());
    // a legend strip is added below the map
    assert!(img.height() > m.frame.rows as u32 * s);
    assert_eq!(img.width(), m.frame.cols as u32 * s);
    // the middle of the first segment is on the path line
    let c = m.frame.cell_at(Point::new(5.0, 2.85)).unwrap();
    let (x, y) = (c.col as u32 * s + s / 2, c.row as u32 * s + s / 2);
    let on_line = (y - 3..=y + 3).any(|py| img.get_pixel(x, py).0 == PATH_RGB);
    assert!(on_line, "no path pixel near (5.0, 2.85)");
    // and not where the path does not go
    assert!((0..img.height()).all(|py| img.get_pixel(20, py).0 != PATH_RGB));
    // the first stop's disc, away from its digit
    let c = m.frame.cell_at(Point::new(7.2, 2.7)).unwrap();
    let (x, y) = (c.col as u32 * s + s / 2, c.row as u32 * s + s / 2);
    let disc = (0..12u32).any(|d| img.get_pixel(x + 9 - d / 4, y + d % 4).0 == STOP_RGB);
    assert!(disc, "no stop disc at the first stop");
    // the final pose faces east: the triangle's tip lies east of the position
    let fc = m.frame.cell_at(Point::new(9.4, 4.5)).unwrap();
    let tip_x = fc.col as u32 * s + s / 2 + 10;
    let row = fc.row as u32 * s + s / 2;
    assert_eq!(img.get_pixel(tip_x, row).0, map_core::render::FINAL_RGB);
    let west_x = fc.col as u32 * s + s / 2 - 12;
    assert_ne!(img.get_pixel(west_x, row).0, map_core::render::FINAL_RGB);
}

#[test]
fn png_is_written_and_read_back() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("render");
    std::fs::create_dir_all(&out).unwrap();
    for name in ["flat-a", "office-b", "house-c"] {
        let m = map(&format!("{name}.scene.json"));
        let path = out.join(format!("{name}.png"));
        let start = m.start_pose.position;
        let inst = &m.instances[m.instances.len() / 2];
        let goal = inst.closest_point(start);
        let walk = [start, Point::new(goal.x, start.y), goal];
        let stops = [(
            Pose::new(goal.x, goal.y, 180.0),
            "move_to_object".to_string(),
        )];
        let overlay = RenderOverlay {
            path: &walk,
            stops: &stops,
            final_pose: Some(Pose::new(goal.x, goal.y, 180.0)),
        };
        render_png(&m, &overlay, &RenderOptions::default(), &path).unwrap();
        let back = image::open(&path).unwrap().to_rgb8();
        assert_eq!(back, render_rgb(&m, &overlay, &RenderOptions::default()));
    }
    let err = render_png(
        &map("flat-a.scene.json"),
        &RenderOverlay::default(),
        &RenderOptions::default(),
        "/nonexistent-dir/x.png",
    )
    .unwrap_err();
    assert!(err.to_string().contains("/nonexistent-dir/x.png"), "{err}");
}
