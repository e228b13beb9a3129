//! Points, poses, headings and polygons in the world frame (metres, x east, y north).

use serde::{Deserialize, Serialize};

/// A point in the world frame, metres: `x` east, `y` north.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Point {
    /// Metres east.
    pub x: f64,
    /// Metres north.
    pub y: f64,
}

impl Point {
    /// A point at (`x`, `y`) metres.
    pub const fn new(x: f64, y: f64) -> Self {
        Self { x, y }
    }

    /// Euclidean distance to `other`, metres.
    pub fn dist(self, other: Point) -> f64 {
        (self.x - other.x).hypot(self.y - other.y)
    }

    /// Whether both coordinates are finite.
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite()
    }

    /// Component-wise sum `self + o`.
    #[allow(clippy::should_implement_trait)] // also implemented; the method reads better in chains
    pub fn add(self, o: Point) -> Point {
        Point::new(self.x + o.x, self.y + o.y)
    }

    /// Component-wise difference `self - o`.
    #[allow(clippy::should_implement_trait)]
    pub fn sub(self, o: Point) -> Point {
        Point::new(self.x - o.x, self.y - o.y)
    }

    /// Both coordinates multiplied by `s`.
    pub fn scale(self, s: f64) -> Point {
        Point::new(self.x * s, self.y * s)
    }

    /// Length of the vector from the origin.
    pub fn norm(self) -> f64 {
        self.x.hypot(self.y)
    }

    /// Dot product with `o`.
    pub fn dot(self, o: Point) -> f64 {
        self.x * o.x + self.y * o.y
    }

    /// 2-D cross product (z of the 3-D one).
    pub fn cross(self, o: Point) -> f64 {
        self.x * o.y - self.y * o.x
    }

    /// Compass heading (degrees, 0 north, 90 east) of the direction from `self` to `to`.
    pub fn heading_to(self, to: Point) -> f64 {
        let d = to.sub(self);
        normalise_heading(d.x.atan2(d.y).to_degrees())
    }

    /// The unit vector of a compass heading (0 = north = +y, 90 = east = +x).
    pub fn from_heading(heading_deg: f64) -> Point {
        let r = heading_deg.to_radians();
        Point::new(r.sin(), r.cos())
    }
}

impl std::ops::Add for Point {
    type Output = Point;
    fn add(self, o: Point) -> Point {
        Point::new(self.x + o.x, self.y + o.y)
    }
}

impl std::ops::Sub for Point {
    type Output = Point;
    fn sub(self, o: Point) -> Point {
        Point::new(self.x - o.x, self.y - o.y)
    }
}

impl std::ops::Mul<f64> for Point {
    type Output = Point;
    fn mul(self, s: f64) -> Point {
        Point::new(self.x * s, self.y * s)
    }
}

impl From<[f64; 2]> for Point {
    fn from(a: [f64; 2]) -> Self {
        Point::new(a[0], a[1])
    }
}

impl From<Point> for [f64; 2] {
    fn from(p: Point) -> Self {
        [p.x, p.y]
    }
}

/// Normalise a compass heading to (-180, 180].
pub fn normalise_heading(h: f64) -> f64 {
    let mut a = h % 360.0;
    if a <= -180.0 {
        a += 360.0;
    } else if a > 180.0 {
        a -= 360.0;
    }
    a
}

/// A robot pose: position and compass heading in degrees (0 north, 90 east, clockwise).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Pose {
    /// Position in the world frame, metres.
    pub position: Point,
    /// Compass heading, degrees (0 north, 90 east, clockwise).
    pub heading: f64,
}

impl Pose {
    /// A pose at (`x`, `y`) metres facing compass `heading` degrees (normalised).
    pub fn new(x: f64, y: f64, heading: f64) -> Self {
        Self {
            position: Point::new(x, y),
            heading: normalise_heading(heading),
        }
    }

    /// `[x, y, heading]`, the form the file formats use.
    pub fn to_array(self) -> [f64; 3] {
        [self.position.x, self.position.y, self.heading]
    }

    /// Unit vector the robot faces.
    pub fn forward(self) -> Point {
        Point::from_heading(self.heading)
    }

    /// Unit vector to the robot's right (heading + 90).
    pub fn right(self) -> Point {
        Point::from_heading(self.heading + 90.0)
    }
}

/// Axis-aligned bounding box in world metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    /// South-west corner (smallest x and y).
    pub min: Point,
    /// North-east corner (largest x and y).
    pub max: Point,
}

impl Aabb {
    /// The smallest box holding all `pts`; `None` when `pts` is empty.
    pub fn from_points(pts: &[Point]) -> Option<Aabb> {
        let first = *pts.first()?;
        let mut b = Aabb {
            min: first,
            max: first,
        };
        for p in &pts[1..] {
            b.min.x = b.min.x.min(p.x);
            b.min.y = b.min.y.min(p.y);
            b.max.x = b.max.x.max(p.x);
            b.max.y = b.max.y.max(p.y);
        }
        Some(b)
    }

    /// Centre of the box.
    pub fn center(&self) -> Point {
        Point::new(
            (self.min.x + self.max.x) / 2.0,
            (self.min.y + self.max.y) / 2.0,
        )
    }

    /// East-west extent, metres.
    pub fn width(&self) -> f64 {
        self.max.x - self.min.x
    }

    /// North-south extent, metres.
    pub fn height(&self) -> f64 {
        self.max.y - self.min.y
    }

    /// Length of the diagonal, metres.
    pub fn diagonal(&self) -> f64 {
        self.width().hypot(self.height())
    }
}

/// A simple polygon (no holes), vertices in order, not closed (last != first).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Polygon(pub Vec<Point>);

impl Polygon {
    /// The vertices, in order.
    pub fn vertices(&self) -> &[Point] {
        &self.0
    }

    /// Even-odd point-in-polygon test (points on the boundary may go either way).
    pub fn contains(&self, p: Point) -> bool {
        let v = &self.0;
        if v.len() < 3 {
            return false;
        }
        let mut inside = false;
        let mut j = v.len() - 1;
        for i in 0..v.len() {
            let (a, b) = (v[i], v[j]);
            if (a.y > p.y) != (b.y > p.y) {
                let x = (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x;
                if p.x < x {
                    inside = !inside;
                }
            }
            j = i;
        }
        inside
    }

    /// Absolute area (shoelace).
    pub fn area(&self) -> f64 {
        let v = &self.0;
        if v.len() < 3 {
            return 0.0;
        }
        let mut s = 0.0;
        for i in 0..v.len() {
            s += v[i].cross(v[(i + 1) % v.len()]);
        }
        s.abs() / 2.0
    }

    /// Area-weighted centroid; the vertex mean for degenerate polygons.
    pub fn centroid(&self) -> Point {
        let v = &self.0;
        let n = v.len();
        if n == 0 {
            return Point::default();
        }
        let mut a = 0.0;
        let mut c = Point::default();
        for i in 0..n {
            let (p, q) = (v[i], v[(i + 1) % n]);
            let cr = p.cross(q);
            a += cr;
            c.x += (p.x + q.x) * cr;
            c.y += (p.y + q.y) * cr;
        }
        if a.abs() < 1e-12 {
            let s = v.iter().fold(Point::default(), |s, p| s.add(*p));
            return s.scale(1.0 / n as f64);
        }
        c.scale(1.0 / (3.0 * a))
    }

    /// Bounding box of the vertices; `None` for an empty polygon.
    pub fn bbox(&self) -> Option<Aabb> {
        Aabb::from_points(&self.0)
    }

    /// Closest point of the polygon's boundary to `p`.
    pub fn closest_boundary_point(&self, p: Point) -> Option<Point> {
        let v = &self.0;
        match v.len() {
            0 => None,
            1 => Some(v[0]),
            n => {
                let mut best: Option<(f64, Point)> = None;
                for i in 0..n {
                    let q = closest_on_segment(p, v[i], v[(i + 1) % n]);
                    let d = q.dist(p);
                    if best.is_none_or(|(bd, _)| d < bd) {
                        best = Some((d, q));
                    }
                }
                best.map(|(_, q)| q)
            }
        }
    }

    /// Distance from `p` to the polygon as a filled region: 0 inside.
    pub fn distance(&self, p: Point) -> f64 {
        if self.contains(p) {
            return 0.0;
        }
        self.closest_boundary_point(p)
            .map_or(f64::INFINITY, |q| q.dist(p))
    }
}

/// The point of segment `a`-`b` closest to `p`.
pub fn closest_on_segment(p: Point, a: Point, b: Point) -> Point {
    let ab = b.sub(a);
    let l2 = ab.dot(ab);
    if l2 <= 0.0 {
        return a;
    }
    let t = (p.sub(a).dot(ab) / l2).clamp(0.0, 1.0);
    a.add(ab.scale(t))
}

/// The corners of a rectangle of `size` = [extent x, extent y] centred at `center`,
/// rotated by `yaw_deg` clockwise (compass sense), in counter-clockwise order.
pub fn oriented_rect(center: Point, size: [f64; 2], yaw_deg: f64) -> Polygon {
    let (hx, hy) = (size[0] / 2.0, size[1] / 2.0);
    // Clockwise rotation by yaw: x' = x cos + y sin, y' = -x sin + y cos.
    let r = yaw_deg.to_radians();
    let (s, c) = r.sin_cos();
    let corners = [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)];
    Polygon(
        corners
            .iter()
            .map(|&(x, y)| Point::new(center.x + x * c + y * s, center.y - x * s + y * c))
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compass_headings_follow_x_east_y_north() {
        let o = Point::new(0.0, 0.0);
        assert!((o.heading_to(Point::new(0.0, 1.0)) - 0.0).abs() < 1e-9);
        assert!((o.heading_to(Point::new(1.0, 0.0)) - 90.0).abs() < 1e-9);
        assert!((o.heading_to(Point::new(0.0, -1.0)) - 180.0).abs() < 1e-9);
        assert!((o.heading_to(Point::new(-1.0, 0.0)) + 90.0).abs() < 1e-9);
        let e = Point::from_heading(90.0);
        assert!((e.x - 1.0).abs() < 1e-9 && e.y.abs() < 1e-9);
    }

    #[test]
    fn right_of_north_is_east() {
        let p = Pose::new(0.0, 0.0, 0.0);
        assert!((p.right().x - 1.0).abs() < 1e-9);
    }

    #[test]
    fn oriented_rect_yaw_is_clockwise() {
        // A 2 x 0 bar rotated 90 degrees clockwise points north-south.
        let r = oriented_rect(Point::new(0.0, 0.0), [2.0, 0.0], 90.0);
        let b = r.bbox().unwrap();
        assert!(b.width() < 1e-9 && (b.height() - 2.0).abs() < 1e-9);
        let sq = oriented_rect(Point::new(1.0, 1.0), [2.0, 1.0], 0.0);
        assert!((sq.area() - 2.0).abs() < 1e-9);
        assert!(sq.contains(Point::new(1.5, 1.2)));
        assert!(!sq.contains(Point::new(2.5, 1.2)));
        assert!((sq.distance(Point::new(3.0, 1.0)) - 1.0).abs() < 1e-9);
        let c = sq.centroid();
        assert!((c.x - 1.0).abs() < 1e-9 && (c.y - 1.0).abs() < 1e-9);
    }

    #[test]
    fn heading_normalises_into_half_open_range() {
        assert_eq!(normalise_heading(180.0), 180.0);
        assert_eq!(normalise_heading(-180.0), 180.0);
        assert_eq!(normalise_heading(270.0), -90.0);
        assert_eq!(normalise_heading(-450.0), -90.0);
    }
}
