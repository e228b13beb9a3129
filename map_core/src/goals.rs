//! Goal points and headings for the spatial words of the function library
//! (design.md, "Where a side is asked for"). Pure functions of the map's
//! geometry and the robot's pose; the planner snaps a goal that lies in an
//! inflated obstacle to the nearest reachable free cell.

use crate::geometry::{closest_on_segment, normalise_heading, Point, Polygon, Pose};
use crate::map::{Instance, Region};

/// Distance beyond a footprint's bounding-box edge for move_north/south/east/west.
pub const SIDE_CLEARANCE_M: f64 = 0.5;

/// A compass side of an object.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The north side (+y).
    North,
    /// The south side (-y).
    South,
    /// The east side (+x).
    East,
    /// The west side (-x).
    West,
}

/// The point of the footprint nearest the robot: `move_to_object` aims here and the
/// planner stops at the nearest reachable free cell, i.e. as close as the robot can get.
pub fn approach_point(robot: Pose, obj: &Instance) -> Point {
    obj.closest_point(robot.position)
}

/// 0.5 m beyond that edge of the footprint's bounding box, on its centre line.
pub fn side_point(obj: &Instance, side: Side) -> Point {
    let b = obj.bbox_m;
    let c = b.center();
    match side {
        Side::North => Point::new(c.x, b.max.y + SIDE_CLEARANCE_M),
        Side::South => Point::new(c.x, b.min.y - SIDE_CLEARANCE_M),
        Side::East => Point::new(b.max.x + SIDE_CLEARANCE_M, c.y),
        Side::West => Point::new(b.min.x - SIDE_CLEARANCE_M, c.y),
    }
}

/// Perpendicular to the robot-to-object line, half the footprint diagonal from the
/// object's centre, on the robot's left (`left = true`) or right as it faces the object.
pub fn lateral_point(robot: Pose, obj: &Instance, left: bool) -> Point {
    let c = obj.center();
    let d = c.sub(robot.position);
    // Facing the object: along d. If the robot stands on the centre, use its heading.
    let dir = if d.norm() > 1e-9 {
        d.scale(1.0 / d.norm())
    } else {
        robot.forward()
    };
    // Left of a direction (dx, dy) in x-east/y-north is (-dy, dx).
    let left_dir = Point::new(-dir.y, dir.x);
    let side = if left { left_dir } else { left_dir.scale(-1.0) };
    c.add(side.scale(obj.bbox_m.diagonal() / 2.0))
}

/// The closest pair of points of two polygons (one on each boundary).
pub fn closest_points(a: &Polygon, b: &Polygon) -> Option<(Point, Point)> {
    let (va, vb) = (a.vertices(), b.vertices());
    if va.is_empty() || vb.is_empty() {
        return None;
    }
    let mut best: Option<(f64, Point, Point)> = None;
    let mut consider = |p: Point, q: Point| {
        let d = p.dist(q);
        if best.is_none_or(|(bd, _, _)| d < bd) {
            best = Some((d, p, q));
        }
    };
    for &p in va {
        for j in 0..vb.len() {
            consider(p, closest_on_segment(p, vb[j], vb[(j + 1) % vb.len()]));
        }
    }
    for &q in vb {
        for i in 0..va.len() {
            consider(closest_on_segment(q, va[i], va[(i + 1) % va.len()]), q);
        }
    }
    best.map(|(_, p, q)| (p, q))
}

/// Midpoint of the two objects' closest footprint points.
pub fn between_point(a: &Instance, b: &Instance) -> Point {
    match closest_points(&a.contour, &b.contour) {
        Some((p, q)) => p.add(q).scale(0.5),
        None => a.center().add(b.center()).scale(0.5),
    }
}

/// Heading that faces the object's footprint centre.
pub fn face_heading(robot: Pose, obj: &Instance) -> f64 {
    robot.position.heading_to(obj.center())
}

/// Heading that puts the object's centre 90 degrees to the robot's left (`left = true`)
/// or right.
pub fn heading_with_object_on(robot: Pose, obj: &Instance, left: bool) -> f64 {
    let bearing = face_heading(robot, obj);
    normalise_heading(if left { bearing + 90.0 } else { bearing - 90.0 })
}

/// Where `move_to` a region aims: its centroid if inside, else the middle of its
/// bounding box, else its first vertex.
pub fn region_point(region: &Region) -> Point {
    let c = region.polygon.centroid();
    if region.polygon.contains(c) {
        return c;
    }
    match region.polygon.bbox() {
        Some(b) if region.polygon.contains(b.center()) => b.center(),
        _ => region.polygon.vertices().first().copied().unwrap_or(c),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::oriented_rect;
    use crate::geometry::Aabb;

    fn inst(c: Point, size: [f64; 2]) -> Instance {
        let contour = oriented_rect(c, size, 0.0);
        Instance {
            id: 1,
            label: "table".into(),
            label_id: 1,
            num_of_same_class: 1,
            colour: None,
            area: 0,
            area_m2: contour.area(),
            bbox: [0; 4],
            bbox_m: contour.bbox().unwrap_or(Aabb { min: c, max: c }),
            centroid: c,
            contour,
        }
    }

    fn close(a: Point, b: Point) -> bool {
        a.dist(b) < 1e-9
    }

    #[test]
    fn sides_are_half_a_metre_beyond_the_box() {
        let t = inst(Point::new(5.0, 5.0), [2.0, 1.0]);
        assert!(close(side_point(&t, Side::North), Point::new(5.0, 6.0)));
        assert!(close(side_point(&t, Side::South), Point::new(5.0, 4.0)));
        assert!(close(side_point(&t, Side::East), Point::new(6.5, 5.0)));
        assert!(close(side_point(&t, Side::West), Point::new(3.5, 5.0)));
    }

    #[test]
    fn left_and_right_are_the_robots_as_it_faces_the_object() {
        // Robot south of the object, looking north: its left is west.
        let t = inst(Point::new(5.0, 5.0), [0.6, 0.8]);
        let robot = Pose::new(5.0, 0.0, 0.0);
        let l = lateral_point(robot, &t, true);
        let r = lateral_point(robot, &t, false);
        assert!(
            (l.x - 4.5).abs() < 1e-9 && (l.y - 5.0).abs() < 1e-9,
            "{l:?}"
        );
        assert!(
            (r.x - 5.5).abs() < 1e-9 && (r.y - 5.0).abs() < 1e-9,
            "{r:?}"
        );
    }

    #[test]
    fn between_is_the_midpoint_of_the_closest_points() {
        let a = inst(Point::new(0.0, 0.0), [2.0, 2.0]);
        let b = inst(Point::new(5.0, 0.0), [2.0, 2.0]);
        let m = between_point(&a, &b);
        assert!((m.x - 2.5).abs() < 1e-9 && m.y.abs() <= 1.0 + 1e-9, "{m:?}");
    }

    #[test]
    fn headings_for_face_and_object_on_a_side() {
        let t = inst(Point::new(3.0, 0.0), [0.5, 0.5]);
        let robot = Pose::new(0.0, 0.0, 0.0);
        assert!((face_heading(robot, &t) - 90.0).abs() < 1e-9);
        // Facing north, an object to the east is on the right.
        assert!((heading_with_object_on(robot, &t, false) - 0.0).abs() < 1e-9);
        assert!((heading_with_object_on(robot, &t, true) - 180.0).abs() < 1e-9);
    }
}
