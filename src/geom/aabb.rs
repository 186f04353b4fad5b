use super::{Point2, Point3, Vector3};

/// An axis-aligned box. An empty box has `min > max` and grows to fit what is added.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Point3,
    pub max: Point3,
}

impl Aabb {
    /// The empty box: contains nothing, and `grow` of any point makes it that point.
    pub fn empty() -> Self {
        Self {
            min: Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
            max: Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY),
        }
    }

    /// The smallest box around `points` (empty for no points).
    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a Point3>) -> Self {
        let mut b = Self::empty();
        for p in points {
            b.grow(p);
        }
        b
    }

    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    pub fn grow(&mut self, p: &Point3) {
        self.min = self.min.inf(p);
        self.max = self.max.sup(p);
    }

    pub fn merge(&self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.inf(&other.min),
            max: self.max.sup(&other.max),
        }
    }

    pub fn extent(&self) -> Vector3 {
        if self.is_empty() {
            Vector3::zeros()
        } else {
            self.max - self.min
        }
    }

    pub fn diagonal(&self) -> f64 {
        self.extent().norm()
    }

    pub fn center(&self) -> Point3 {
        nalgebra::center(&self.min, &self.max)
    }

    /// Squared distance between this box and `other` (0 where they overlap).
    #[inline(always)]
    pub fn distance_squared_to_box(&self, other: &Aabb) -> f64 {
        (0..3)
            .map(|i| {
                let gap = (other.min[i] - self.max[i])
                    .max(self.min[i] - other.max[i])
                    .max(0.0);
                gap * gap
            })
            .sum()
    }

    /// The box grown by `d` on every side.
    pub fn inflated(&self, d: f64) -> Aabb {
        let grow = Vector3::new(d, d, d);
        Aabb {
            min: self.min - grow,
            max: self.max + grow,
        }
    }

    /// Squared distance from `p` to the box (0 inside).
    #[inline(always)]
    pub fn distance_squared(&self, p: &Point3) -> f64 {
        let mut d = 0.0;
        for i in 0..3 {
            let e = (self.min[i] - p[i]).max(0.0).max(p[i] - self.max[i]);
            d += e * e;
        }
        d
    }
}

/// An axis-aligned box in the XY plane (the bounds of planar segments and regions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb2 {
    pub min: Point2,
    pub max: Point2,
}

impl Aabb2 {
    /// The box of one point.
    pub fn point(p: Point2) -> Self {
        Self { min: p, max: p }
    }

    /// Grows the box to contain `p`.
    pub fn add(&mut self, p: Point2) {
        self.min = Point2::new(self.min.x.min(p.x), self.min.y.min(p.y));
        self.max = Point2::new(self.max.x.max(p.x), self.max.y.max(p.y));
    }

    /// Smallest box containing both.
    pub fn union(&self, o: &Aabb2) -> Aabb2 {
        let mut b = *self;
        b.add(o.min);
        b.add(o.max);
        b
    }

    /// The box grown by `d` on every side.
    pub fn expanded(&self, d: f64) -> Aabb2 {
        Aabb2 {
            min: Point2::new(self.min.x - d, self.min.y - d),
            max: Point2::new(self.max.x + d, self.max.y + d),
        }
    }

    /// Euclidean distance between the boxes (0 when they overlap): a lower bound of the distance
    /// between anything inside them.
    pub fn distance(&self, o: &Aabb2) -> f64 {
        let dx = (o.min.x - self.max.x).max(self.min.x - o.max.x).max(0.0);
        let dy = (o.min.y - self.max.y).max(self.min.y - o.max.y).max(0.0);
        dx.hypot(dy)
    }

    /// Distance from a point to the box (0 inside).
    pub fn point_distance(&self, p: Point2) -> f64 {
        self.distance(&Aabb2::point(p))
    }

    /// Centre of the box.
    pub fn center(&self) -> Point2 {
        nalgebra::center(&self.min, &self.max)
    }

    /// Whether the segment `a`–`b` has a point in the closed box (Liang–Barsky clipping).
    pub fn meets_segment(&self, a: Point2, b: Point2) -> bool {
        let d = b - a;
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for (p, q) in [
            (-d.x, a.x - self.min.x),
            (d.x, self.max.x - a.x),
            (-d.y, a.y - self.min.y),
            (d.y, self.max.y - a.y),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    return false;
                }
            } else {
                let t = q / p;
                if p < 0.0 {
                    t0 = t0.max(t);
                } else {
                    t1 = t1.min(t);
                }
                if t0 > t1 {
                    return false;
                }
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distance_to_box_matches_hand_values() {
        let b = Aabb::from_points(&[Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 2.0, 3.0)]);
        assert_eq!(b.distance_squared(&Point3::new(0.5, 1.0, 1.0)), 0.0);
        assert_eq!(b.distance_squared(&Point3::new(2.0, 1.0, 1.0)), 1.0);
        assert_eq!(
            b.distance_squared(&Point3::new(-1.0, 4.0, 5.0)),
            1.0 + 4.0 + 4.0
        );
        assert!(Aabb::empty().is_empty());
        assert_eq!(b.diagonal(), 14f64.sqrt());
    }
}
