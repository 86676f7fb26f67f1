//! Instances: trees whose simplices stay in their objects' own space, reached by rays mapped
//! into that space. An object moved by an affine transform `x_w = A·x_o + b` (the
//! "Transformations" of the course notes) is traced by mapping each world ray
//! `X(t) = C + t·d` to `X_o(t) = A⁻¹(C − b) + t·A⁻¹d`: the same t reaches the same point (an
//! affine map keeps the ray's parameter), barycentric coordinates are affine invariants, and the
//! normal n̂ of eq. 6 is a covector, mapped back by the inverse transpose, `A⁻ᵀ·n̂` normalized.
//! So a frame of an animation that moves objects reuses the trees built for the first frame:
//! nothing per simplex is done again.
//!
//! Every query returns the least (t, id) over the accepted hits of all instances, as one tree
//! over all the simplices would (each tree's answer does not depend on its shape, and the
//! instances' answers are merged by (t, id)). The trees of a scene and the map of each object
//! are kept apart, so that frames share the trees ([`Instances::moved`]).

use super::simplex::Bounds;
use super::tree::Bvh;
use crate::linalg::{add, cofactor_matrix, det, identity, mat_vec, norm, scale, transpose};
use crate::linalg::{Matrix, Vector};
use crate::ray::{Hit, Ray};
use std::ops::Range;
use std::sync::Arc;

/// The map from world space into an object's own space, `x_o = m·x_w + c`: for the object
/// transform `x_w = A·x_o + b`, `m = A⁻¹` and `c = −A⁻¹·b`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToObject<const N: usize> {
    /// `A⁻¹`.
    pub m: Matrix<N>,
    /// `−A⁻¹·b`.
    pub c: Vector<N>,
    /// `A⁻ᵀ = mᵀ`, which maps normals (covectors) out to world space.
    pub mt: Matrix<N>,
    /// Whether A reverses handedness (det A < 0). The scene then swaps the first two vertices
    /// of each simplex to keep its normal pointing the same way (see [`ToObject::normal`]).
    pub flip: bool,
    /// The condition number `‖A‖·‖A⁻¹‖` (Frobenius norms): how much the rounding of a mapped
    /// ray may grow.
    pub cond: f64,
}

impl<const N: usize> ToObject<N> {
    /// The inverse of the affine map `x ↦ a·x + b`, with `A⁻ᵀ = cofactor(A)/det A`; `None`
    /// when `a` is singular, or its determinant or inverse is not finite (a map too badly
    /// scaled to invert this way).
    pub fn inverse_of(a: &Matrix<N>, b: &Vector<N>) -> Option<Self> {
        let d = det(a);
        let mt = cofactor_matrix(a).map(|row| scale(&row, 1.0 / d));
        let m = transpose(&mt);
        let c = scale(&mat_vec(&m, b), -1.0);
        let finite = m.iter().flatten().chain(&c).all(|x| x.is_finite());
        let frobenius = |m: &Matrix<N>| m.iter().flatten().map(|x| x * x).sum::<f64>().sqrt();
        (d != 0.0 && d.is_finite() && finite).then_some(ToObject {
            m,
            c,
            mt,
            flip: d < 0.0,
            cond: frobenius(a) * frobenius(&m),
        })
    }

    /// The map of an object traced in its own space: [`ToObject::inverse_of`] the transform,
    /// `None` for the identity, exactly (world space is its own space), and when there is no
    /// inverse (a scene refuses such a transform for an object with simplices).
    pub fn of_transform(a: &Matrix<N>, b: &Vector<N>) -> Option<Self> {
        let identity = *a == identity::<N>() && b.iter().all(|&x| x == 0.0);
        if identity {
            None
        } else {
            Self::inverse_of(a, b)
        }
    }

    /// The world ray in object space: the same t reaches the same point.
    #[inline]
    pub fn ray(&self, r: &Ray<N>) -> Ray<N> {
        Ray {
            origin: add(&mat_vec(&self.m, &r.origin), &self.c),
            dir: mat_vec(&self.m, &r.dir),
        }
    }

    /// The world unit normal of a simplex whose object-space unit normal is `n`: `A⁻ᵀ·n`
    /// normalized, negated when A reverses handedness (the simplex's vertices are swapped in
    /// both spaces, which turns its object-space normal around while the world one keeps its
    /// side: the generalized cross product of `A·e_k` is `det A·A⁻ᵀ` times that of `e_k`).
    /// Zero for a zero `n` (a degenerate simplex).
    #[inline]
    pub fn normal(&self, n: &Vector<N>) -> Vector<N> {
        let w = mat_vec(&self.mt, n);
        let len = norm(&w);
        if len == 0.0 {
            return [0.0; N];
        }
        scale(&w, if self.flip { -1.0 / len } else { 1.0 / len })
    }
}

/// One tree as the rays of some objects reach it.
#[derive(Debug, Clone, PartialEq)]
struct Instance<const N: usize> {
    /// Index of the tree.
    tree: usize,
    /// World to object space (`None`: the tree is in world space).
    map: Option<ToObject<N>>,
    /// The ids this instance answers for, when not every id the tree holds.
    only: Option<Vec<Range<u32>>>,
    /// The world box of its objects, padded (see [`Instance::reaches`]).
    bounds: Bounds<N>,
}

impl<const N: usize> Instance<N> {
    /// Whether `id` is one of this instance's.
    #[inline]
    fn owns(&self, id: u32) -> bool {
        self.only
            .as_ref()
            .is_none_or(|r| r.iter().any(|r| r.contains(&id)))
    }

    /// `accept` restricted to this instance's ids.
    ///
    /// The one closure type of a query's `F`: the tree's traversal is instantiated per closure
    /// type and is most of the code compiled per N, so the one-instance and the many-instance
    /// paths of a query share it instead of instantiating it twice.
    #[inline]
    fn accepting<'a, F: Fn(u32) -> bool>(&'a self, accept: &'a F) -> impl Fn(u32) -> bool + 'a {
        move |id| self.owns(id) && accept(id)
    }

    /// Whether the world ray can meet this instance's objects with t in [tmin, tmax]: the
    /// slab test of its padded world box, which costs less than mapping the ray and entering
    /// the tree. The box is padded by [`BOUNDS_PAD`] of its diagonal and its farthest
    /// coordinate, far beyond the rounding of the world vertices and of the inverse map of a
    /// well-conditioned transform (a map whose condition number exceeds [`MAX_CULL_COND`] is
    /// not culled), so a hit the tree would give is not culled.
    #[inline]
    fn reaches(&self, r: &Ray<N>, tmin: f64, tmax: f64) -> bool {
        let (lo, hi) = &self.bounds;
        let (mut near, mut far) = (tmin, tmax);
        for i in 0..N {
            if r.dir[i] == 0.0 {
                if !(r.origin[i] >= lo[i] && r.origin[i] <= hi[i]) {
                    return false;
                }
                continue;
            }
            let inv = 1.0 / r.dir[i];
            let (a, b) = ((lo[i] - r.origin[i]) * inv, (hi[i] - r.origin[i]) * inv);
            near = near.max(a.min(b));
            far = far.min(a.max(b));
        }
        near <= far
    }

    /// The ray in the tree's space.
    #[inline]
    fn ray(&self, r: &Ray<N>) -> Ray<N> {
        self.map.as_ref().map_or(*r, |m| m.ray(r))
    }

    /// The rays in the tree's space, borrowed when no map moves them.
    fn rays<'a>(&self, rays: &'a [Ray<N>]) -> std::borrow::Cow<'a, [Ray<N>]> {
        match &self.map {
            None => std::borrow::Cow::Borrowed(rays),
            Some(m) => std::borrow::Cow::Owned(rays.iter().map(|r| m.ray(r)).collect()),
        }
    }

    /// A hit of the tree with its normal in world space.
    #[inline]
    fn to_world(&self, mut h: Hit<N>) -> Hit<N> {
        if let Some(m) = &self.map {
            h.normal = m.normal(&h.normal);
        }
        h
    }
}

/// Relative padding of an instance's world box (see [`Instance::reaches`]).
const BOUNDS_PAD: f64 = 1e-6;
/// Largest condition number of a map whose instance is culled by its box: a mapped ray's
/// rounding, ~ε·cond·|C|, stays far below the pad unless the eye is ~10⁵ boxes away.
const MAX_CULL_COND: f64 = 1e4;

/// `a` is a better hit than `b`: the least (t, id) wins.
#[inline]
fn better<const N: usize>(a: &Hit<N>, b: &Option<Hit<N>>) -> bool {
    b.as_ref()
        .is_none_or(|b| a.t < b.t || (a.t == b.t && a.prim < b.prim))
}

/// The trees of a scene, each holding the simplices of some objects (global ids) in those
/// objects' own space, and how the rays reach them: per object, its tree and its map.
#[derive(Debug, Clone)]
pub struct Instances<const N: usize> {
    trees: Vec<Arc<Bvh<N>>>,
    /// Per global simplex id, where its object's tree keeps it ([`Bvh::id_slots`]), or
    /// `u32::MAX` for a degenerate simplex, which no tree holds.
    slots: Arc<Vec<u32>>,
    /// Per object, the index of its tree.
    tree_of: Arc<Vec<u32>>,
    /// First global id of each object's simplices.
    offsets: Arc<Vec<u32>>,
    /// Per object, world to object space (`None`: traced in world space).
    maps: Vec<Option<ToObject<N>>>,
    /// The objects grouped by (tree, map).
    list: Vec<Instance<N>>,
}

impl<const N: usize> Instances<N> {
    /// The instances of `trees` for objects whose first global ids are `offsets` (ids
    /// `0..slots.len()` in all), object k held by tree `tree_of[k]`, mapped into its space by
    /// `maps[k]` and lying in the world box `boxes[k]` (the box of its world vertices); `slots`
    /// as [`Bvh::id_slots`] gives them for each tree's ids.
    ///
    /// # Panics
    /// If the lengths of `tree_of`, `offsets`, `maps` and `boxes` differ, or a tree index is
    /// out of range.
    pub fn new(
        trees: Vec<Arc<Bvh<N>>>,
        slots: Arc<Vec<u32>>,
        tree_of: Arc<Vec<u32>>,
        offsets: Arc<Vec<u32>>,
        (maps, boxes): (Vec<Option<ToObject<N>>>, &[Bounds<N>]),
    ) -> Self {
        assert!(tree_of.len() == offsets.len() && maps.len() == offsets.len());
        assert_eq!(boxes.len(), offsets.len());
        assert!(tree_of.iter().all(|&t| (t as usize) < trees.len()));
        let mut list: Vec<Instance<N>> = Vec::new();
        // Per instance, how many objects it answers for; per tree, how many objects it is
        // the tree of, and how many of its simplices they own (a tree may also hold stale
        // copies of objects that moved to another tree: see `moved_with`).
        let (mut members, mut held) = (Vec::new(), vec![0usize; trees.len()]);
        let mut owned = vec![0usize; trees.len()];
        for (k, (&t, map)) in tree_of.iter().zip(&maps).enumerate() {
            let ids = offsets[k]..offsets.get(k + 1).copied().unwrap_or(slots.len() as u32);
            if ids.is_empty() {
                continue;
            }
            let tree = t as usize;
            held[tree] += 1;
            owned[tree] += slots[ids.start as usize..ids.end as usize]
                .iter()
                .filter(|&&s| s != u32::MAX)
                .count();
            let merge = |(a, b): &Bounds<N>, (c, d): &Bounds<N>| -> Bounds<N> {
                (
                    std::array::from_fn(|i| a[i].min(c[i])),
                    std::array::from_fn(|i| b[i].max(d[i])),
                )
            };
            match list.iter().position(|i| i.tree == tree && i.map == *map) {
                Some(at) => {
                    members[at] += 1;
                    list[at].bounds = merge(&list[at].bounds, &boxes[k]);
                    let only = list[at].only.as_mut().expect("made with a range");
                    match only.last_mut() {
                        Some(last) if last.end == ids.start => last.end = ids.end,
                        _ => only.push(ids),
                    }
                }
                None => {
                    members.push(1);
                    list.push(Instance {
                        tree,
                        map: *map,
                        only: Some(vec![ids]),
                        bounds: boxes[k],
                    });
                }
            }
        }
        // An instance that answers for every simplex its tree holds needs no filter; boxes
        // are padded.
        for (i, m) in list.iter_mut().zip(members) {
            if m == held[i.tree] && owned[i.tree] == trees[i.tree].len() {
                i.only = None;
            }
            let (lo, hi) = &mut i.bounds;
            let reach = (0..N)
                .map(|k| (hi[k] - lo[k]) + lo[k].abs().max(hi[k].abs()))
                .fold(0.0, f64::max);
            for k in 0..N {
                lo[k] -= BOUNDS_PAD * reach;
                hi[k] += BOUNDS_PAD * reach;
            }
            // A badly conditioned map may move a mapped ray by more than the pad: no culling.
            if i.map.is_some_and(|m| !(m.cond <= MAX_CULL_COND)) {
                i.bounds = ([f64::NEG_INFINITY; N], [f64::INFINITY; N]);
            }
        }
        Instances {
            trees,
            slots,
            tree_of,
            offsets,
            maps,
            list,
        }
    }

    /// The same trees reached through other maps, the objects now in the world boxes
    /// `boxes` (an animation frame that moves objects).
    pub fn moved(&self, maps: Vec<Option<ToObject<N>>>, boxes: &[Bounds<N>]) -> Self {
        Self::new(
            self.trees.clone(),
            Arc::clone(&self.slots),
            Arc::clone(&self.tree_of),
            Arc::clone(&self.offsets),
            (maps, boxes),
        )
    }

    /// [`Instances::moved`], the objects `members` now held by `tree` (built anew over them;
    /// its ids are theirs), whose slots `slots` gives for every id.
    pub fn moved_with(
        &self,
        (maps, boxes): (Vec<Option<ToObject<N>>>, &[Bounds<N>]),
        tree: Bvh<N>,
        members: &[usize],
        slots: Vec<u32>,
    ) -> Self {
        let mut trees = self.trees.clone();
        let mut tree_of = self.tree_of.to_vec();
        // The new tree takes the place of one only the members used, else comes last.
        let unused =
            |t: usize| (0..tree_of.len()).all(|k| tree_of[k] as usize != t || members.contains(&k));
        let at = (0..trees.len()).find(|&t| unused(t)).unwrap_or(trees.len());
        members.iter().for_each(|&k| tree_of[k] = at as u32);
        if at == trees.len() {
            trees.push(Arc::new(tree));
        } else {
            trees[at] = Arc::new(tree);
        }
        Self::new(
            trees,
            Arc::new(slots),
            Arc::new(tree_of),
            Arc::clone(&self.offsets),
            (maps, boxes),
        )
    }

    /// First global id of each object's simplices.
    pub fn offsets(&self) -> &[u32] {
        &self.offsets
    }

    /// The trees.
    pub fn trees(&self) -> &[Arc<Bvh<N>>] {
        &self.trees
    }

    /// The tree holding object k's simplices.
    pub fn tree(&self, k: usize) -> &Arc<Bvh<N>> {
        &self.trees[self.tree_of[k] as usize]
    }

    /// The trees some object uses.
    fn used(&self) -> impl Iterator<Item = &Bvh<N>> {
        let used = |t: usize| self.tree_of.iter().any(|&u| u as usize == t);
        (self.trees.iter().enumerate()).filter_map(move |(t, b)| used(t).then_some(&**b))
    }

    /// Object k's map from world space into its tree's space (`None`: world space).
    pub fn map(&self, k: usize) -> Option<&ToObject<N>> {
        self.maps[k].as_ref()
    }

    /// Per global id, the slot of its simplex in its tree, `u32::MAX` for one no tree holds
    /// (degenerate).
    pub fn slots(&self) -> &[u32] {
        &self.slots
    }

    /// Whether the simplex with global id `g` is held (it is not degenerate).
    #[inline]
    pub fn holds(&self, g: u32) -> bool {
        self.slots[g as usize] != u32::MAX
    }

    /// The world unit normal (eq. 6) of the simplex with global id `g` (zero for a degenerate
    /// one; its tree stores it rounded to f32), bit for bit the normal of its hits.
    #[inline]
    pub fn flat_normal(&self, g: u32) -> Vector<N> {
        let slot = self.slots[g as usize];
        if slot == u32::MAX {
            return [0.0; N];
        }
        let k = self.offsets.partition_point(|&o| o <= g) - 1;
        let n = self.trees[self.tree_of[k] as usize].slot_normal(slot);
        self.maps[k].as_ref().map_or(n, |m| m.normal(&n))
    }

    /// Nearest hit with t in (tmin, tmax) among the simplices whose id passes `accept`: the
    /// least (t, id), as [`Bvh::closest_hit`] over all the simplices would give it.
    ///
    /// One ray at a time is the cold path (clipped hits traced again, edges, probes; camera
    /// rays go in packets, [`Instances::closest_hits`]), so `accept` is a `dyn`: every caller
    /// shares one instantiation of the traversal per N. `accept` runs only on a hit nearer
    /// than the best so far: the indirect call costs nothing measurable.
    pub fn closest_hit(
        &self,
        ray: &Ray<N>,
        tmin: f64,
        tmax: f64,
        accept: &dyn Fn(u32) -> bool,
    ) -> Option<Hit<N>> {
        let mut best: Option<Hit<N>> = None;
        for i in &self.list {
            // Later instances need only reach the best t (inclusive: an equal t with a
            // smaller id wins).
            let hi = best.map_or(tmax, |b| b.t.next_up().min(tmax));
            if self.list.len() > 1 && !i.reaches(ray, tmin, hi) {
                continue;
            }
            let tree = &self.trees[i.tree];
            let r = i.ray(ray);
            let hit = tree.closest_hit(&r, tmin, hi, i.accepting(&accept));
            if let Some(h) = hit.map(|h| i.to_world(h)) {
                if better(&h, &best) {
                    best = Some(h);
                }
            }
        }
        best
    }

    /// [`Instances::closest_hit`] for every ray of `rays` into `out` (same length), traced in
    /// packets ([`Bvh::closest_hits`]).
    ///
    /// # Panics
    /// If `out` and `rays` differ in length.
    pub fn closest_hits(
        &self,
        rays: &[Ray<N>],
        tmin: f64,
        tmax: f64,
        accept: impl Fn(u32) -> bool,
        out: &mut [Option<Hit<N>>],
    ) {
        assert_eq!(rays.len(), out.len(), "closest_hits: rays and out differ");
        if let [i] = &self.list[..] {
            // One instance (a scene of untransformed objects, or of one object): its answers.
            let tree = &self.trees[i.tree];
            tree.closest_hits(&i.rays(rays), tmin, tmax, i.accepting(&accept), out);
            if i.map.is_some() {
                out.iter_mut().flatten().for_each(|h| *h = i.to_world(*h));
            }
            return;
        }
        out.fill(None);
        let mut hits = vec![None; rays.len()];
        for i in &self.list {
            // The packet skips the instances none of its rays can reach.
            if !rays.iter().any(|r| i.reaches(r, tmin, tmax)) {
                continue;
            }
            let tree = &self.trees[i.tree];
            let mapped = i.rays(rays);
            tree.closest_hits(&mapped, tmin, tmax, i.accepting(&accept), &mut hits);
            for (o, h) in out.iter_mut().zip(&hits) {
                if let Some(h) = h.map(|h| i.to_world(h)) {
                    if better(&h, o) {
                        *o = Some(h);
                    }
                }
            }
        }
    }

    /// Whether any simplex whose id passes `accept` and lies outside `skip` is hit with t in
    /// (tmin, tmax) ([`Bvh::any_hit`] in every instance). A `dyn` `accept`, as for
    /// [`Instances::closest_hit`]: shadow rays of the packets go through [`Instances::any_hits`].
    pub fn any_hit(
        &self,
        ray: &Ray<N>,
        tmin: f64,
        tmax: f64,
        accept: &dyn Fn(u32) -> bool,
        skip: Range<u32>,
    ) -> bool {
        let one = self.list.len() == 1;
        self.list.iter().any(|i| {
            if !one && !i.reaches(ray, tmin, tmax) {
                return false;
            }
            self.trees[i.tree].any_hit(&i.ray(ray), tmin, tmax, i.accepting(&accept), skip.clone())
        })
    }

    /// [`Instances::any_hit`] for every ray of `rays` with its own `tmax[i]`, into `out`.
    ///
    /// # Panics
    /// If `rays`, `tmax` and `out` differ in length.
    pub fn any_hits(
        &self,
        rays: &[Ray<N>],
        tmin: f64,
        tmax: &[f64],
        accept: impl Fn(u32) -> bool,
        skip: Range<u32>,
        out: &mut [bool],
    ) {
        assert!(
            rays.len() == out.len() && rays.len() == tmax.len(),
            "any_hits: rays, tmax and out differ in length"
        );
        if let [i] = &self.list[..] {
            let accept = i.accepting(&accept);
            return self.trees[i.tree].any_hits(&i.rays(rays), tmin, tmax, accept, skip, out);
        }
        out.fill(false);
        let mut blocked = vec![false; rays.len()];
        for i in &self.list {
            if !rays.iter().zip(tmax).any(|(r, &t)| i.reaches(r, tmin, t)) {
                continue;
            }
            let tree = &self.trees[i.tree];
            let mapped = i.rays(rays);
            let accept = i.accepting(&accept);
            tree.any_hits(&mapped, tmin, tmax, accept, skip.clone(), &mut blocked);
            for (o, b) in out.iter_mut().zip(&blocked) {
                *o |= b;
            }
        }
    }

    /// Number of simplices held (the ones that are not degenerate).
    pub fn len(&self) -> usize {
        self.slots.iter().filter(|&&s| s != u32::MAX).count()
    }

    /// Whether no tree holds a simplex.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of (8-wide) nodes of the trees the objects use.
    pub fn node_count(&self) -> usize {
        self.used().map(Bvh::node_count).sum()
    }

    /// Memory of the trees the objects use ([`Bvh::memory_bytes`]), in bytes.
    pub fn memory_bytes(&self) -> usize {
        self.used().map(Bvh::memory_bytes).sum()
    }

    /// Number of flat cells of the trees the objects use.
    pub fn cell_count(&self) -> usize {
        self.used().map(Bvh::cell_count).sum()
    }

    /// How many instances the rays visit (one per tree and map).
    pub fn instance_count(&self) -> usize {
        self.list.len()
    }
}

#[cfg(test)]
mod tests;
