//! The index of a scene's objects, built behind one constructor ([`build_index`], as pbrt's
//! `CreateAccelerator`): the scene says what is there ([`AccelObject`]: a mesh, where it is
//! held, what its shape is known to be), this module decides how to index it — which objects
//! share a tree and which are held in their own space ([`INSTANCE_MIN`]), the binned SAH build
//! or the Morton build ([`MORTON_MIN`]), flat cells ([`MIN_CELL`]), what the convexity
//! certificates of shadow rays will be found from ([`ShapeHints::certificate`]; they are found
//! at the first trace that needs them, not here) — and what the build costs in memory
//! ([`bvh_bytes`]).
//!
//! The steps, for each group of objects sharing a tree:
//! 1. each simplex prepared once, in simplex order: its build record (box, global id) and the
//!    f32 rows of its block lane (`sah_bvh`);
//! 2. the flat pieces of hypercubes and of meshes small enough to search, as flat cells;
//! 3. the SAH tree (or, from [`MORTON_MIN`] simplices, the Morton tree), whose blocks are
//!    filled from the rows of step 1;
//! 4. after the scene has shared its objects ([`Built::finish`]): the trees' exact sources
//!    (the meshes again, for the rare unsure lanes) and the [`Instances`] that reach them.

use super::{
    prefetch_of, simplex_bounds, Bounds, BuildRef, Bvh, ExactSource, FlatCell, Instances, Lane,
    PreparedSimplex, ToObject, EXACT_ROWS_MAX_BYTES, MORTON_MIN,
};
use crate::convex::Certificate;
use crate::linalg::Vector;
use crate::mesh::Mesh;
use rayon::prelude::*;
use std::sync::Arc;

/// Fewest simplices an object with a transform needs to be traced in its own space, in a tree
/// of its own that frames moving it share ([`Instances`]); smaller ones are traced in world
/// space, in the tree of the untransformed objects (each instance costs a ray a box test, and
/// a rebuild of a few thousand simplices costs little).
pub const INSTANCE_MIN: usize = 4096;

/// Fewest simplices a flat piece needs to be held as a flat cell: below this, testing its
/// blocks costs less than a walk (an N-cube's facet has (N−1)! simplices: N ≥ 5).
const MIN_CELL: usize = 24;
/// Largest mesh whose flat pieces are looked for (matching their ridges costs a sort).
const MAX_FLAT_SEARCH: usize = 1 << 18;

/// How many simplices ahead the passes over a mesh in simplex order ask for their vertices
/// ([`warm_vertices`]).
pub(crate) const AHEAD: usize = 8;

/// Bytes the BVH of `count` simplices in R^n needs at the peak of its build. The SAH build
/// holds each simplex's record (prepared matrix and origin, normal, bounds), the copies handed
/// to the BVH and the leaf blocks; the Morton build (from [`MORTON_MIN`] simplices) the blocks,
/// the sort keys, the blocks' boxes and the nodes.
pub fn bvh_bytes(n: usize, count: f64) -> f64 {
    let prepared = ((n * n + n) * 8) as f64;
    let per_simplex = if count >= MORTON_MIN as f64 {
        prepared + (24 + 4 * n) as f64
    } else {
        3.0 * prepared + (5 * n * 8 + 16) as f64
    };
    count * per_simplex
}

/// Whether an object's flat facets are worth looking for, to hold them as flat cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlatFacets {
    /// Its facets are known to be flat pieces of several simplices (the N-cube): always.
    Always,
    /// It may have some (a mesh): when it has at most 2¹⁸ simplices (matching its ridges costs
    /// a sort).
    Search,
    /// It has none worth a cell (spheres, simplices, cross-polytopes, elevation maps).
    Never,
}

/// What the scene knows of an object's shape that the index uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ShapeHints {
    /// The mesh bounds a convex body (a generated polytope, or one moved by an affine map).
    pub known_convex: bool,
    /// Whether its convexity certificate is worth finding for shadow rays (not for an
    /// elevation map: a graph over a box, an open surface, where the test would cost more than
    /// it saves).
    pub certify: bool,
    /// Whether its flat facets are looked for.
    pub flat_facets: FlatFacets,
}

impl ShapeHints {
    /// The convexity certificate of an object with these hints, held by the index in world
    /// space (`own` = `None`) or in its own space with the vertices `own` through `map`: to be
    /// found at the first trace that needs it when shadow rays will use it (`options.shadows`)
    /// and it is worth finding, else never ([`Certificate`]).
    pub fn certificate<const N: usize>(
        &self,
        options: &AccelOptions,
        own: Option<Arc<Vec<Vector<N>>>>,
        map: Option<&ToObject<N>>,
    ) -> Certificate<N> {
        match options.shadows && self.certify {
            true => Certificate::lazy(own, map.is_some_and(|m| m.flip), self.known_convex),
            false => Certificate::none(),
        }
    }
}

/// How the index is built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AccelOptions {
    /// Shadow rays will be traced: the objects' convexity certificates will be found (at the
    /// first trace that needs them, [`ShapeHints::certificate`]).
    pub shadows: bool,
    /// Fewest simplices of a tree built by the Morton build ([`MORTON_MIN`]).
    pub morton_min: usize,
    /// Fewest simplices of a transformed object held in its own space ([`INSTANCE_MIN`]).
    pub instance_min: usize,
}

impl AccelOptions {
    /// The default thresholds, with or without shadow rays.
    pub fn new(shadows: bool) -> Self {
        AccelOptions {
            shadows,
            morton_min: MORTON_MIN,
            instance_min: INSTANCE_MIN,
        }
    }

    /// Whether a transformed object of `simplices` simplices is held in its own space (before
    /// its transform) rather than in world space.
    pub fn own_space(&self, simplices: usize) -> bool {
        simplices >= self.instance_min
    }
}

/// One object as the index sees it.
pub struct AccelObject<'a, const N: usize> {
    /// Its mesh in world space, simplices in the order given (ids refer to it).
    pub mesh: &'a mut Mesh<N>,
    /// Its vertices in its own space (before its transform), when it is held there; `map`
    /// takes world rays into that space.
    pub own: Option<Vec<Vector<N>>>,
    /// World to object space, when it is held in its own space.
    pub map: Option<ToObject<N>>,
    /// What its shape is known to be.
    pub hints: ShapeHints,
}

/// Where the trees find the scene's meshes again once the scene shares them (for the exact
/// test of the rare unsure lanes, [`ExactSource`]).
pub trait Meshes<const N: usize>: Send + Sync + 'static {
    /// The mesh of object `k`, in world space.
    fn mesh(&self, k: usize) -> &Mesh<N>;
}

/// The first global id of each object's simplices, and their total.
pub fn offsets_of<'a, const N: usize>(
    meshes: impl Iterator<Item = &'a Mesh<N>>,
) -> (Vec<u32>, u64) {
    let mut offsets = Vec::new();
    let mut total = 0u64;
    for m in meshes {
        offsets.push(total as u32);
        total += m.simplices.len() as u64;
    }
    (offsets, total)
}

/// The trees of a scene's objects, built, before the scene shares its objects with them
/// ([`Built::finish`]).
pub struct Built<const N: usize> {
    trees: Vec<Bvh<N>>,
    groups: Vec<Vec<usize>>,
    tree_of: Vec<u32>,
    slots: Vec<u32>,
    offsets: Vec<u32>,
    own: Vec<Option<Arc<Vec<Vector<N>>>>>,
    maps: Vec<Option<ToObject<N>>>,
    convex: Vec<Certificate<N>>,
}

/// Builds the index of `objects` (global ids from `offsets`): the untransformed objects and the
/// small transformed ones in one tree in world space, each object held in its own space in a
/// tree of its own (objects without simplices, surfaces, in none).
pub fn build_index<const N: usize>(
    objects: &mut [AccelObject<'_, N>],
    offsets: &[u32],
    options: &AccelOptions,
) -> Built<N> {
    let total = offsets_of(objects.iter().map(|o| &*o.mesh)).1 as usize;
    // The trees are built in the objects' own space: the vertices before the transform (the
    // simplices keep the order the transform gave them), swapped in for the build.
    let swap_own = |objects: &mut [AccelObject<'_, N>]| {
        for o in objects.iter_mut() {
            if let Some(v) = &mut o.own {
                std::mem::swap(&mut o.mesh.vertices, v);
            }
        }
    };
    swap_own(objects);
    let alone = |k: &usize| objects[*k].own.is_some();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let untransformed: Vec<usize> = (0..objects.len()).filter(|k| !alone(k)).collect();
    if !untransformed.is_empty() {
        groups.push(untransformed);
    }
    groups.extend((0..objects.len()).filter(alone).map(|k| vec![k]));
    let mut tree_of = vec![0u32; objects.len()];
    let mut slots = vec![u32::MAX; total];
    let mut trees = Vec::with_capacity(groups.len());
    for (t, members) in groups.iter().enumerate() {
        let tree = group_tree(objects, (offsets, &mut slots), members, options);
        members.iter().for_each(|&k| tree_of[k] = t as u32);
        trees.push(tree);
    }
    swap_own(objects);
    let own: Vec<_> = objects
        .iter_mut()
        .map(|o| o.own.take().map(Arc::new))
        .collect();
    // The certificates are found in the space the trees hold the objects in.
    let convex = objects
        .iter()
        .zip(&own)
        .map(|(o, own)| o.hints.certificate(options, own.clone(), o.map.as_ref()))
        .collect();
    Built {
        trees,
        groups,
        tree_of,
        slots,
        offsets: offsets.to_vec(),
        own,
        maps: objects.iter().map(|o| o.map).collect(),
        convex,
    }
}

impl<const N: usize> Built<N> {
    /// Per object, its convexity certificate, to be found at the first trace that needs it
    /// ([`ShapeHints::certificate`]).
    pub fn certificates(&self) -> &[Certificate<N>] {
        &self.convex
    }

    /// Per global id, the slot of its simplex in its tree ([`Bvh::id_slots`]), `u32::MAX` for
    /// a degenerate one.
    pub fn slots(&self) -> &[u32] {
        &self.slots
    }

    /// How many simplices no tree holds (they have no volume).
    pub fn skipped(&self) -> usize {
        self.slots.len() - self.trees.iter().map(Bvh::len).sum::<usize>()
    }

    /// The instances of the trees, once the scene shares its objects (`meshes`, the meshes the
    /// index was built from): the trees find their exact simplices in them (and the vertices of
    /// the objects held in their own space, kept for it); object k lies in the world box
    /// `boxes[k]`.
    pub fn finish<M: Meshes<N>>(self, meshes: &Arc<M>, boxes: &[Bounds<N>]) -> Instances<N> {
        let mut trees = self.trees;
        let exact_rows =
            trees.iter().map(Bvh::exact_rows_bytes).sum::<usize>() <= EXACT_ROWS_MAX_BYTES;
        for (tree, members) in trees.iter_mut().zip(&self.groups) {
            tree.set_exact(exact_source(meshes, &self.offsets, members, &self.own));
            if exact_rows {
                tree.keep_exact_rows();
            }
        }
        Instances::new(
            trees.into_iter().map(Arc::new).collect(),
            Arc::new(self.slots),
            Arc::new(self.tree_of),
            Arc::new(self.offsets),
            (self.maps, boxes),
        )
    }
}

/// The tree of `members`, objects held in world space, built anew over them for a frame that
/// moved them, the other objects kept where `instances` holds them.
pub struct Rebuilt<const N: usize> {
    tree: Bvh<N>,
    members: Vec<usize>,
    slots: Vec<u32>,
}

/// [`build_index`] of a frame that moved some objects, for the objects `members` held in world
/// space by `instances` (the index of the frame before; no object in its own space among
/// them): their tree built anew over their moved meshes (global ids from `offsets`; their
/// certificates are the caller's: [`ShapeHints::certificate`] for those that moved).
pub fn rebuild_members<const N: usize>(
    instances: &Instances<N>,
    objects: &mut [AccelObject<'_, N>],
    offsets: &[u32],
    members: &[usize],
    options: &AccelOptions,
) -> Rebuilt<N> {
    let mut slots = instances.slots().to_vec();
    for &k in members {
        let end = offsets.get(k + 1).map_or(slots.len(), |&e| e as usize);
        slots[offsets[k] as usize..end].fill(u32::MAX);
    }
    let tree = group_tree(objects, (offsets, &mut slots), members, options);
    Rebuilt {
        tree,
        members: members.to_vec(),
        slots,
    }
}

impl<const N: usize> Rebuilt<N> {
    /// How many simplices no tree holds.
    pub fn skipped(&self) -> usize {
        self.slots.par_iter().filter(|&&s| s == u32::MAX).count()
    }

    /// The instances of `instances` with the rebuilt tree, the objects reached through `maps`
    /// and lying in the world boxes `boxes`, once the scene shares its moved objects
    /// (`meshes`).
    pub fn finish<M: Meshes<N>>(
        self,
        instances: &Instances<N>,
        meshes: &Arc<M>,
        (maps, boxes): (Vec<Option<ToObject<N>>>, &[Bounds<N>]),
    ) -> Instances<N> {
        let mut tree = self.tree;
        let offsets = instances.offsets();
        tree.set_exact(exact_source(meshes, offsets, &self.members, &[]));
        // The same simplices as the frame before: exact rows if its trees kept them.
        if instances.trees().iter().any(|t| t.has_exact_rows()) {
            tree.keep_exact_rows();
        }
        instances.moved_with((maps, boxes), tree, &self.members, self.slots)
    }
}

/// The tree of the objects `members` (their meshes in the space the tree is built in), with
/// their global ids (`offsets`), its slots written into `slots` ([`Bvh::fill_id_slots`]): the
/// SAH build, or the Morton build from `options.morton_min` simplices.
fn group_tree<const N: usize>(
    objects: &[AccelObject<'_, N>],
    (offsets, slots): (&[u32], &mut [u32]),
    members: &[usize],
    options: &AccelOptions,
) -> Bvh<N> {
    let count: usize = members
        .iter()
        .map(|&k| objects[k].mesh.simplices.len())
        .sum();
    if count < options.morton_min {
        let tree = sah_bvh(objects, offsets, members);
        tree.fill_id_slots(slots);
        return tree;
    }
    // Local index i → (member, simplex): the members' simplices one after the other.
    let mut starts = Vec::with_capacity(members.len());
    let mut at = 0;
    for &k in members {
        starts.push(at);
        at += objects[k].mesh.simplices.len();
    }
    let split = |i: usize| {
        let m = starts.partition_point(|&s| s <= i) - 1;
        (members[m], i - starts[m])
    };
    let domain = members
        .par_iter()
        .flat_map(|&k| objects[k].mesh.vertices.par_iter())
        .map(|v| (*v, *v))
        .reduce(empty_box, merge_boxes);
    let tree = Bvh::build_morton_with_ids(
        count,
        domain,
        |i| {
            let (k, s) = split(i);
            objects[k].mesh.simplex_points(s)
        },
        |i| {
            let (k, s) = split(i);
            offsets[k] + s as u32
        },
        ExactSource::none(),
    );
    tree.fill_id_slots(slots);
    tree
}

/// Where the tree over the objects `members` finds the exact simplex of a global id: their
/// meshes in `meshes`, with the vertices of `own[k]` for an object held in its own space.
fn exact_source<const N: usize, M: Meshes<N>>(
    meshes: &Arc<M>,
    offsets: &[u32],
    members: &[usize],
    own: &[Option<Arc<Vec<Vector<N>>>>],
) -> ExactSource<N> {
    // (first global id, object, its vertices in its own space when it has them)
    type Part<const N: usize> = (u32, usize, Option<Arc<Vec<Vector<N>>>>);
    let parts: Vec<Part<N>> = members
        .iter()
        .map(|&k| (offsets[k], k, own.get(k).cloned().flatten()))
        .collect();
    let meshes = Arc::clone(meshes);
    ExactSource::new(move |g| {
        let (off, k, own) = &parts[parts.partition_point(|p| p.0 <= g) - 1];
        let mesh = meshes.mesh(*k);
        let vertices = own.as_deref().unwrap_or(&mesh.vertices);
        let idx = &mesh.simplices[(g - off) as usize];
        PreparedSimplex::new(&idx.map(|i| vertices[i as usize]))
            .expect("a simplex prepared once prepares again")
    })
}

/// The points of global simplex g of the objects whose first global ids are `offsets`.
fn simplex_at<const N: usize>(
    objects: &[AccelObject<'_, N>],
    offsets: &[u32],
    g: usize,
) -> [Vector<N>; N] {
    let o = offsets.partition_point(|&off| off as usize <= g) - 1;
    objects[o].mesh.simplex_points(g - offsets[o] as usize)
}

/// The empty box, the identity of [`merge_boxes`].
pub fn empty_box<const N: usize>() -> Bounds<N> {
    ([f64::INFINITY; N], [f64::NEG_INFINITY; N])
}

/// The box of two boxes (exact, so any reduction order gives the same bits).
pub fn merge_boxes<const N: usize>((a, b): Bounds<N>, (c, d): Bounds<N>) -> Bounds<N> {
    (
        std::array::from_fn(|k| a[k].min(c[k])),
        std::array::from_fn(|k| b[k].max(d[k])),
    )
}

/// The box of the simplices of `meshes` that the index holds (`slots` not `u32::MAX`; global
/// ids from `offsets`), exact in any order.
pub fn held_box<'a, const N: usize>(
    meshes: impl Iterator<Item = &'a Mesh<N>>,
    offsets: &[u32],
    slots: &[u32],
) -> Bounds<N> {
    let kept = |(mesh, &off): (&Mesh<N>, &u32)| {
        let slots = &slots[off as usize..][..mesh.simplices.len()];
        (0..slots.len())
            .into_par_iter()
            .filter(|&s| slots[s] != u32::MAX)
            .map(|s| {
                warm_vertices(mesh, s + AHEAD);
                simplex_bounds(&mesh.simplex_points(s))
            })
            .reduce(empty_box, merge_boxes)
    };
    meshes.zip(offsets).map(kept).fold(empty_box(), merge_boxes)
}

/// The SAH-built BVH over every non-degenerate simplex of the objects `members` (global ids
/// from `offsets`).
fn sah_bvh<const N: usize>(
    objects: &[AccelObject<'_, N>],
    offsets: &[u32],
    members: &[usize],
) -> Bvh<N> {
    // Each simplex's build record (holding, for now, its global id, or `DROPPED` for a
    // degenerate simplex) and the rows its block lane will hold, in one parallel pass in
    // simplex order, so that the fill does not prepare the simplices again. (The rows, N² f32 per simplex, are alive until the
    // blocks are filled; a lane's other part, the simplex's first vertex, is read from the
    // mesh.)
    const DROPPED: u32 = u32::MAX;
    let mut refs: Vec<BuildRef<N>> = Vec::new();
    let mut rows: Vec<[[f32; N]; N]> = Vec::new();
    let mut cells = Vec::new();
    let mut dropped = 0;
    for &k in members {
        let (o, off) = (&objects[k], offsets[k]);
        let mesh = &*o.mesh;
        let search = match o.hints.flat_facets {
            FlatFacets::Always => true,
            FlatFacets::Search => mesh.simplices.len() <= MAX_FLAT_SEARCH,
            FlatFacets::Never => false,
        };
        let count = mesh.simplices.len();
        let record = |s: usize, r: &mut BuildRef<N>, row: &mut [[f32; N]; N]| {
            // (The pass runs over increasing s in each task.)
            warm_vertices(mesh, s + AHEAD);
            let pts = mesh.simplex_points(s);
            if let Some(p) = PreparedSimplex::new(&pts) {
                *r = BuildRef::new(off + s as u32, &simplex_bounds(&pts));
                *row = Lane::rows_of(&p);
            }
        };
        let none = BuildRef::new(DROPPED, &([0.0; N], [0.0; N]));
        let mut mine = vec![none; count];
        let mut my_rows = vec![[[0.0; N]; N]; count];
        (mine.par_iter_mut().zip(&mut my_rows).enumerate())
            .for_each(|(s, (r, row))| record(s, r, row));
        dropped += mine.par_iter().filter(|r| r.id == DROPPED).count();
        if search {
            // The normals are made again where they are needed (no list of them is kept): a
            // kept simplex's is its hyperplane's ([`PreparedSimplex::normal`]).
            let normal = |s: usize| match mine[s].id {
                DROPPED => None,
                _ => crate::geometry::hyperplane(&mesh.simplex_points(s))
                    .ok()
                    .map(|h| h.normal),
            };
            for piece in crate::mesh::flat::flat_pieces(mesh, normal, MIN_CELL) {
                cells.push((off, piece));
            }
        }
        if refs.is_empty() {
            (refs, rows) = (mine, my_rows);
        } else {
            refs.extend_from_slice(&mine);
            rows.extend_from_slice(&my_rows);
        }
    }
    if dropped > 0 {
        // `retain` visits the elements in order, once each: row k goes with record k.
        let mut k = 0;
        rows.retain(|_| {
            k += 1;
            refs[k - 1].id != DROPPED
        });
        refs.retain(|r| r.id != DROPPED);
    }
    // The global ids, and the records numbered as the build's inputs.
    let ids: Vec<u32> = (refs.par_iter_mut().enumerate())
        .map(|(i, r)| std::mem::replace(&mut r.id, i as u32))
        .collect();
    // The flat pieces as cells over the build's inputs (`ids`: the global ids of the
    // non-degenerate simplices, increasing; a piece has no degenerate simplex).
    let cells = cells
        .into_iter()
        .map(|(off, piece): (u32, Vec<u32>)| {
            let members = piece
                .iter()
                .map(|&s| {
                    ids.binary_search(&(off + s))
                        .expect("a piece's simplex is kept") as u32
                })
                .collect();
            let points = piece
                .iter()
                .map(|&s| simplex_at(objects, offsets, (off + s) as usize))
                .collect();
            FlatCell { members, points }
        })
        .collect();
    let prepare = |_, g: u32| {
        PreparedSimplex::new(&simplex_at(objects, offsets, g as usize))
            .expect("a simplex prepared once prepares again")
    };
    // The first vertex of global simplex g, and what it is read through.
    let first = |g: u32| {
        let o = offsets.partition_point(|&off| off <= g) - 1;
        let mesh = &*objects[o].mesh;
        (mesh, &mesh.simplices[(g - offsets[o]) as usize])
    };
    let lane = |i: usize, g: u32| {
        let (mesh, idx) = first(g);
        Lane {
            rows: rows[i],
            x0: mesh.vertices[idx[0] as usize],
        }
    };
    // What `lane(i, g)` will read: the rows and the simplex's vertex indices, then (`near`)
    // its first vertex.
    let warm = |i: usize, g: u32, near: bool| {
        let (mesh, idx) = first(g);
        if near {
            prefetch_of(&mesh.vertices[idx[0] as usize]);
        } else {
            prefetch_of(idx);
            prefetch_of(&rows[i]);
        }
    };
    Bvh::build_with_cells_borrowing(ids, refs, cells, (prepare, lane, warm))
}

/// Asks for the vertices of simplex `s` of `mesh` (if there is one) ahead of their use: in a
/// large mesh they lie anywhere, and a pass over its simplices would wait for each in turn.
fn warm_vertices<const N: usize>(mesh: &Mesh<N>, s: usize) {
    for &v in mesh.simplices.get(s).into_iter().flatten() {
        if let Some(x) = mesh.vertices.get(v as usize) {
            prefetch_of(x);
        }
    }
}
