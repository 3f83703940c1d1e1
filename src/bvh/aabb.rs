use glam::Vec3;

/// Axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    /// The identity of `union` and `grow`: contains nothing, so growing it by a point gives that point.
    pub const EMPTY: Aabb = Aabb { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY };

    pub fn new(min: Vec3, max: Vec3) -> Aabb {
        Aabb { min, max }
    }

    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    /// Edge lengths; negative on an empty box.
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// Zero for an empty or flat box, so SAH weights stay finite for `EMPTY`.
    pub fn surface_area(&self) -> f32 {
        let d = self.extent().max(Vec3::ZERO);
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }

    pub fn centroid(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Index (0, 1, 2) of the longest edge; x when the box has no extent.
    pub fn largest_axis(&self) -> usize {
        self.extent().max_position()
    }

    /// True when `o` lies inside `self` (boundaries included).
    pub fn contains(&self, o: &Aabb) -> bool {
        self.min.cmple(o.min).all() && o.max.cmple(self.max).all()
    }

    /// Finite and non-inverted: the boxes the builder is meant to receive.
    pub fn is_valid(&self) -> bool {
        self.min.is_finite() && self.max.is_finite() && self.min.cmple(self.max).all()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_is_identity_of_union_and_has_zero_area() {
        let b = Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 3.0, 4.0));
        assert_eq!(Aabb::EMPTY.union(&b), b);
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
        assert!(!Aabb::EMPTY.is_valid());
        let mut g = Aabb::EMPTY;
        g.grow(b.min);
        g.grow(b.max);
        assert_eq!(g, b);
    }

    #[test]
    fn area_centroid_axis_contains() {
        let b = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(b.surface_area(), 22.0);
        assert_eq!(b.centroid(), Vec3::new(0.5, 1.0, 1.5));
        assert_eq!(b.largest_axis(), 2);
        assert!(b.contains(&Aabb::new(Vec3::splat(0.5), Vec3::ONE)));
        assert!(!b.contains(&Aabb::new(Vec3::splat(0.5), Vec3::splat(2.5))));
    }
}
