use super::*;
use crate::accel::tests::*;
use crate::accel::{Instances, ToObject};
use crate::linalg::{add, det, mat_vec};
use std::sync::Arc;

/// Three objects' soups in their own space, with contiguous global ids: objects 0 and 1 in
/// one tree (as a build puts untransformed objects), object 2 in its own.
type Objects<const N: usize> = Vec<Vec<[[f64; N]; N]>>;

fn objects<const N: usize>(r: &mut TestRng) -> (Objects<N>, Vec<u32>, Vec<Arc<Bvh<N>>>) {
    let counts = [40usize, 25, 60];
    let mut objs: Objects<N> = Vec::new();
    for (k, &count) in counts.iter().enumerate() {
        let mut o: Vec<[[f64; N]; N]> = soup::<N>(r, count).into_iter().map(|s| s.0).collect();
        o.truncate(count);
        if k == 1 {
            // An exact duplicate of object 0's first simplex: ties across objects.
            o[0] = objs[0][0];
        }
        objs.push(o);
    }
    let offsets: Vec<u32> = vec![0, 40, 65];
    let tree = |members: &[usize]| {
        let (mut pts, mut ids) = (vec![], vec![]);
        for &k in members {
            for (s, p) in objs[k].iter().enumerate() {
                pts.push(*p);
                ids.push(offsets[k] + s as u32);
            }
        }
        Bvh::from_simplices(&pts, &ids)
    };
    let trees = vec![Arc::new(tree(&[0, 1])), Arc::new(tree(&[2]))];
    (objs, offsets, trees)
}

/// The world simplex of an object-space one under x ↦ a·x + b, its vertices in the same
/// order (a mirror turns its generalized cross product around with det a, as
/// [`ToObject::normal`] does).
fn moved<const N: usize>(p: &[[f64; N]; N], (a, b): &(Matrix<N>, Vector<N>)) -> [[f64; N]; N] {
    p.map(|x| add(&mat_vec(a, &x), b))
}

fn instances_answer_as_the_world_space_simplices<const N: usize>() {
    let mut r = rng(4100 + N as u64);
    let (objs, offsets, trees) = objects::<N>(&mut r);
    let total = objs.iter().map(Vec::len).sum::<usize>();
    let mut slots = vec![u32::MAX; total];
    trees.iter().for_each(|t| t.fill_id_slots(&mut slots));
    let slots = Arc::new(slots);
    let (tree_of, offs) = (Arc::new(vec![0, 0, 1]), Arc::new(offsets.clone()));
    let identity = (crate::linalg::identity::<N>(), [0.0; N]);
    for round in 0..4 {
        // Each object's transform: the identity, a random stretch-rotation-shift, or that
        // with a mirror (det < 0).
        let transforms: Vec<(Matrix<N>, Vector<N>)> = (0..3)
            .map(|k| {
                let choice = (round + k) % 3;
                if choice == 0 {
                    return identity;
                }
                let (mut a, b) = random_affine::<N>(&mut r, 1);
                if choice == 2 {
                    a[0] = a[0].map(|x| -x);
                }
                (a, b)
            })
            .collect();
        let maps: Vec<Option<ToObject<N>>> = transforms
            .iter()
            .map(|(a, b)| ToObject::of_transform(a, b))
            .collect();
        // The world boxes of the moved objects: only a box exactly the vertices' (the pad
        // must make up for the rounding of the inverse map).
        let boxes: Vec<Bounds<N>> = (0..3)
            .map(|k| {
                let pts: Vec<Vector<N>> = objs[k]
                    .iter()
                    .flat_map(|p| moved(p, &transforms[k]))
                    .collect();
                simplex_bounds(&pts)
            })
            .collect();
        let inst = Instances::new(
            trees.clone(),
            Arc::clone(&slots),
            Arc::clone(&tree_of),
            Arc::clone(&offs),
            (maps.clone(), &boxes),
        );
        assert_eq!(inst.len(), total);
        assert!(inst.instance_count() >= 2);
        // The exact answer: each object's simplices in its own space against the ray mapped
        // there, the least (t, id) over all, normals mapped out.
        let own: Vec<Vec<(PreparedSimplex<N>, u32)>> = (0..3)
            .map(|k| {
                let ids = (0..objs[k].len()).map(|s| offsets[k] + s as u32);
                objs[k]
                    .iter()
                    .zip(ids)
                    .map(|(p, id)| (PreparedSimplex::new(p).unwrap(), id))
                    .collect()
            })
            .collect();
        let exact = |ray: &Ray<N>, tmax: f64, accept: &dyn Fn(u32) -> bool| {
            let mut best: Option<Hit<N>> = None;
            for k in 0..3 {
                let r = maps[k].map_or(*ray, |m| m.ray(ray));
                if let Some(mut h) = brute(&own[k], &r, 0.0, tmax, accept) {
                    if let Some(m) = &maps[k] {
                        h.normal = m.normal(&h.normal);
                    }
                    if best.is_none_or(|b| h.t < b.t || (h.t == b.t && h.prim < b.prim)) {
                        best = Some(h);
                    }
                }
            }
            best
        };
        // The independent reference: the simplices moved into world space.
        let world: Vec<(PreparedSimplex<N>, u32)> = (0..3)
            .flat_map(|k| {
                let (t, offsets) = (&transforms[k], &offsets);
                let ids = (0..objs[k].len()).map(move |s| offsets[k] + s as u32);
                objs[k]
                    .iter()
                    .zip(ids)
                    .map(move |(p, id)| (PreparedSimplex::new(&moved(p, t)).unwrap(), id))
            })
            .collect();
        let mut rays = Vec::new();
        for case in 0..600 {
            let origin = random_vector::<N>(&mut r, 6.0);
            let k = case % 3;
            let p = moved(&objs[k][r.random_range(0..objs[k].len())], &transforms[k]);
            let dir = crate::linalg::sub(&plane_point(&mut r, &p, 0.0, 1.0), &origin);
            rays.push(Ray { origin, dir });
        }
        // And rays in random directions, most of which miss some instances' boxes.
        for _ in 0..300 {
            let origin = random_vector::<N>(&mut r, 6.0);
            rays.push(Ray {
                origin,
                dir: random_unit(&mut r),
            });
        }
        let odd = |id: u32| id % 3 != 1;
        let (mut agree, mut hits) = (0, 0);
        for ray in &rays {
            let got = inst.closest_hit(ray, 0.0, f64::INFINITY, &|_| true);
            assert_eq!(
                got,
                exact(ray, f64::INFINITY, &|_| true),
                "N={N} round {round}"
            );
            let filtered = inst.closest_hit(ray, 0.0, f64::INFINITY, &odd);
            assert_eq!(
                filtered,
                exact(ray, f64::INFINITY, &odd),
                "N={N} round {round}"
            );
            // Any hit before t = 2: as the exact answer says.
            let any = inst.any_hit(ray, 0.0, 2.0, &|_| true, 0..0);
            assert_eq!(any, exact(ray, 2.0, &|_| true).is_some());
            let reference = brute(&world, ray, 0.0, f64::INFINITY, |_| true);
            if let (Some(g), Some(w)) = (got, reference) {
                hits += 1;
                if g.prim == w.prim {
                    agree += 1;
                    // Rows rounded to f32 in each space: the hit points differ by ~10⁻⁷ of
                    // the simplex, over the cosine of the incidence along the ray, and the
                    // coordinates by that times the simplex's aspect (random simplices in 7D
                    // have aspects of tens).
                    let cos = crate::linalg::dot(&w.normal, &ray.dir).abs()
                        / crate::linalg::norm(&ray.dir);
                    let tol = 1e-6 / cos;
                    assert!((g.t - w.t).abs() <= tol * w.t.abs().max(1.0), "N={N}: t");
                    for i in 0..N {
                        assert!((g.normal[i] - w.normal[i]).abs() < 1e-6, "N={N}: normal");
                        let db = (g.bary[i] - w.bary[i]).abs();
                        assert!(db < 100.0 * tol, "N={N}: bary {db}, cos {cos}");
                    }
                }
            } else {
                assert_eq!(got.is_some(), reference.is_some(), "N={N}: hit or miss");
            }
            if let Some(h) = got {
                let g = h.prim;
                assert_eq!(inst.flat_normal(g), h.normal, "N={N}: the hit's normal");
            }
        }
        assert!(hits > 300, "N={N}: {hits} hits");
        assert!(agree * 100 >= hits * 99, "N={N}: {agree} of {hits} agree");
        // The packet queries give the one-ray answers.
        let mut out = vec![None; rays.len()];
        inst.closest_hits(&rays, 0.0, f64::INFINITY, odd, &mut out);
        let one: Vec<_> = rays
            .iter()
            .map(|ray| inst.closest_hit(ray, 0.0, f64::INFINITY, &odd))
            .collect();
        assert_eq!(out, one, "N={N} round {round}");
        let tmax: Vec<f64> = (0..rays.len())
            .map(|i| 0.5 + (i % 7) as f64 * 0.3)
            .collect();
        let mut blocked = vec![false; rays.len()];
        inst.any_hits(&rays, 0.0, &tmax, |_| true, 40..65, &mut blocked);
        for (i, ray) in rays.iter().enumerate() {
            let skip = |id: u32| !(40..65).contains(&id);
            assert_eq!(
                blocked[i],
                exact(ray, tmax[i], &skip).is_some(),
                "N={N} ray {i}"
            );
        }
        // Moved: the same trees through other maps.
        let again = inst.moved(maps.clone(), &boxes);
        assert!((again.trees().iter().zip(inst.trees())).all(|(a, b)| Arc::ptr_eq(a, b)));
        assert_eq!(
            again.closest_hit(&rays[0], 0.0, f64::INFINITY, &|_| true),
            one_hit(&inst, &rays[0])
        );
    }
}

fn one_hit<const N: usize>(inst: &Instances<N>, ray: &Ray<N>) -> Option<Hit<N>> {
    inst.closest_hit(ray, 0.0, f64::INFINITY, &|_| true)
}

#[test]
fn instances_answer_as_the_world_space_simplices_in_every_dimension() {
    for_each_dim!(instances_answer_as_the_world_space_simplices);
}

fn maps_are_the_inverse_transforms<const N: usize>() {
    let mut r = rng(4200 + N as u64);
    for case in 0..50 {
        let (mut a, b) = random_affine::<N>(&mut r, 1);
        if case % 2 == 1 {
            a[N - 1] = a[N - 1].map(|x| -x);
        }
        let m = ToObject::of_transform(&a, &b).unwrap();
        assert_eq!(m.flip, det(&a) < 0.0);
        // x_o ↦ world ↦ x_o, and a ray's points at every t.
        let x = random_vector::<N>(&mut r, 2.0);
        let w = add(&mat_vec(&a, &x), &b);
        let back = add(&mat_vec(&m.m, &w), &m.c);
        for i in 0..N {
            assert!((back[i] - x[i]).abs() < 1e-12 * (1.0 + x[i].abs()));
        }
        let ray = Ray {
            origin: random_vector(&mut r, 3.0),
            dir: random_vector(&mut r, 1.0),
        };
        let o = m.ray(&ray);
        let t = 0.7;
        let (p, q) = (ray.at(t), o.at(t));
        let q_world = add(&mat_vec(&a, &q), &b);
        for i in 0..N {
            assert!((p[i] - q_world[i]).abs() < 1e-11 * (1.0 + p[i].abs()));
        }
        // A simplex's world normal is its object-space normal mapped, also when a mirror
        // swaps its first two vertices in both spaces (as a scene does).
        let mut s = random_simplex::<N>(&mut r, &[0.0; N], 1.0);
        if m.flip {
            s.swap(0, 1);
        }
        let (Some(po), Some(pw)) = (
            PreparedSimplex::new(&s),
            PreparedSimplex::new(&moved(&s, &(a, b))),
        ) else {
            continue;
        };
        let n = m.normal(&po.normal());
        for i in 0..N {
            assert!(
                (n[i] - pw.normal()[i]).abs() < 1e-9,
                "N={N} case {case}: {n:?} {:?}",
                pw.normal()
            );
        }
    }
    let id = crate::linalg::identity::<N>();
    assert!(
        ToObject::of_transform(&id, &[0.0; N]).is_none(),
        "the identity is world space"
    );
    let mut flat = id;
    flat[0] = [0.0; N];
    assert!(
        ToObject::of_transform(&flat, &[0.0; N]).is_none(),
        "a singular map has none"
    );
    assert!(
        ToObject::of_transform(&id, &[1.0; N]).is_some(),
        "a shift is a map"
    );
}

#[test]
fn maps_are_the_inverse_transforms_in_every_dimension() {
    for_each_dim!(maps_are_the_inverse_transforms);
}
