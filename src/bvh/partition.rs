//! In-place splitting of a primitive range. Boxes and caller indices live in two arrays moved in
//! lockstep: the binning passes then stream only the boxes.

use super::box_a::BoxA;

/// Bounds of a primitive set and of its (doubled) centroids.
#[derive(Clone, Copy, Debug)]
pub(super) struct SetBounds {
    pub bounds: BoxA,
    pub centroids: BoxA,
}

impl SetBounds {
    pub fn of(prims: &[BoxA]) -> SetBounds {
        let mut set = SetBounds { bounds: BoxA::EMPTY, centroids: BoxA::EMPTY };
        for p in prims {
            set.bounds = set.bounds.union(p);
            set.centroids.grow(p.centroid2());
        }
        set
    }

    pub fn merge(&mut self, o: &SetBounds) {
        self.bounds = self.bounds.union(&o.bounds);
        self.centroids = self.centroids.union(&o.centroids);
    }
}

/// Moves the primitives that satisfy `goes_left` to the front and returns how many there are with
/// the centroid bounds of both sides. Branch-free (Lomuto with an unconditional swap): the side of
/// a primitive is close to a coin flip high in the tree, where a branch would mispredict half the time.
pub(super) fn partition(
    prims: &mut [BoxA],
    indices: &mut [u32],
    goes_left: impl Fn(&BoxA) -> bool,
) -> (usize, [BoxA; 2]) {
    let mut centroids = [BoxA::EMPTY; 2];
    let mut mid = 0;
    for i in 0..prims.len() {
        let p = prims[i];
        let left = goes_left(&p);
        centroids[usize::from(!left)].grow(p.centroid2());
        // [mid, i) all go right, so when `p` does too this swaps two right-going primitives.
        prims[i] = prims[mid];
        prims[mid] = p;
        indices.swap(i, mid);
        mid += usize::from(left);
    }
    (mid, centroids)
}

/// Halves the primitives by centroid along the largest centroid axis. Ties are broken by caller
/// index so the result does not depend on the selection algorithm's handling of equal keys.
pub(super) fn median_split(
    prims: &mut [BoxA],
    indices: &mut [u32],
    centroids: &BoxA,
) -> (usize, usize, [SetBounds; 2]) {
    let axis = (centroids.hi - centroids.lo).max_position();
    let mid = prims.len() / 2;
    let mut keyed: Vec<(BoxA, u32)> = prims.iter().copied().zip(indices.iter().copied()).collect();
    keyed.select_nth_unstable_by(mid, |(a, ia), (b, ib)| {
        let (ca, cb) = (a.centroid2()[axis], b.centroid2()[axis]);
        ca.total_cmp(&cb).then(ia.cmp(ib))
    });
    for ((p, i), (kp, ki)) in prims.iter_mut().zip(indices.iter_mut()).zip(keyed) {
        (*p, *i) = (kp, ki);
    }
    let (left, right) = prims.split_at(mid);
    (axis, mid, [SetBounds::of(left), SetBounds::of(right)])
}
