//! The builder's working box: `Aabb` on 16-byte `Vec3A`s, so unions and centroids are single SIMD ops.

use glam::Vec3A;

use super::Aabb;

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct BoxA {
    pub lo: Vec3A,
    pub hi: Vec3A,
}

impl BoxA {
    /// The identity of `union` and `grow`, like `Aabb::EMPTY`.
    pub const EMPTY: BoxA = BoxA { lo: Vec3A::INFINITY, hi: Vec3A::NEG_INFINITY };

    pub fn grow(&mut self, p: Vec3A) {
        self.lo = self.lo.min(p);
        self.hi = self.hi.max(p);
    }

    pub fn union(&self, o: &BoxA) -> BoxA {
        BoxA { lo: self.lo.min(o.lo), hi: self.hi.max(o.hi) }
    }

    /// Twice the centroid: binning only needs positions relative to each other, and this saves the halving.
    pub fn centroid2(&self) -> Vec3A {
        self.lo + self.hi
    }

    /// Same formula as `Aabb::surface_area`: zero for empty or flat boxes.
    pub fn surface_area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec3A::ZERO);
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }
}

impl From<&Aabb> for BoxA {
    fn from(b: &Aabb) -> BoxA {
        BoxA { lo: b.min.into(), hi: b.max.into() }
    }
}

impl From<&BoxA> for Aabb {
    fn from(b: &BoxA) -> Aabb {
        Aabb::new(b.lo.into(), b.hi.into())
    }
}
