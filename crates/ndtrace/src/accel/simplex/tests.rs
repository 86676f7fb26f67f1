use super::*;
use crate::accel::tests::*;

fn intersect_agrees_with_geometry<const N: usize>() {
    let mut r = rng(1000 + N as u64);
    let (mut hits, mut misses, mut near_edge) = (0, 0, 0);
    for case in 0..3000 {
        let pts = random_simplex::<N>(&mut r, &[0.0; N], 2.0);
        let Some(ps) = PreparedSimplex::new(&pts) else {
            assert!(hyperplane(&pts).is_err());
            continue;
        };
        let plane = hyperplane(&pts).unwrap();
        assert_eq!(ps.normal(), plane.normal, "N={N}");
        assert_eq!(ps.origin(), pts[0]);
        let origin = random_vector::<N>(&mut r, 4.0);
        let target = plane_point(&mut r, &pts, -0.12, 1.0);
        let dir = scale(
            &crate::linalg::sub(&target, &origin),
            r.random_range(0.2..3.0),
        );
        let ray = Ray { origin, dir };
        let (tmin, tmax) = if case % 4 == 0 {
            (0.5, 2.0)
        } else {
            (0.0, f64::INFINITY)
        };
        let got = ps.intersect(&ray, tmin, tmax);
        // Independent computation: eq. of section "Ray Tracing" + Gram/Cramer barycentrics.
        let t = ray_hyperplane(&origin, &dir, &pts).unwrap();
        let mut bary = [0.0; 9];
        barycentric(&ray.at(t), &pts, &mut bary).unwrap();
        let min_bary = bary[..N].iter().cloned().fold(f64::INFINITY, f64::min);
        let expect = t > tmin && t < tmax && min_bary >= 0.0;
        if min_bary.abs() <= 1e-9 || (t - tmin).abs() < 1e-9 || (t - tmax).abs() < 1e-9 {
            near_edge += 1;
        } else {
            assert_eq!(
                got.is_some(),
                expect,
                "N={N} case {case}: t={t} bary={bary:?}"
            );
        }
        if let Some((gt, gb)) = got {
            hits += 1;
            assert!(
                (gt - t).abs() <= 1e-9 * t.abs().max(1.0),
                "N={N}: t {gt} vs {t}"
            );
            for k in 0..N {
                assert!(
                    (gb[k] - bary[k]).abs() <= 1e-9,
                    "N={N}: bary {gb:?} vs {bary:?}"
                );
            }
            let s: f64 = gb.iter().sum();
            assert!((s - 1.0).abs() < 1e-12);
        } else {
            misses += 1;
        }
        // A direction inside the hyperplane is parallel: a miss.
        let along = crate::linalg::sub(&pts[1], &pts[0]);
        assert_eq!(
            ps.intersect(
                &Ray { origin, dir: along },
                f64::NEG_INFINITY,
                f64::INFINITY
            ),
            None
        );
        assert_eq!(
            ps.intersect(
                &Ray {
                    origin,
                    dir: [0.0; N]
                },
                f64::NEG_INFINITY,
                f64::INFINITY
            ),
            None
        );
    }
    assert!(
        hits > 400 && misses > 400 && near_edge < 30,
        "N={N}: {hits} {misses} {near_edge}"
    );
}

#[test]
fn accel_prepared_simplex_intersect_agrees_with_geometry() {
    for_each_dim!(intersect_agrees_with_geometry);
}

#[test]
fn accel_degenerate_simplices_are_rejected() {
    assert!(PreparedSimplex::<3>::new(&[[0.0; 3], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]).is_none());
    assert!(PreparedSimplex::<2>::new(&[[1.0, 2.0], [1.0, 2.0]]).is_none());
    assert!(PreparedSimplex::<2>::new(&[[f64::NAN, 0.0], [1.0, 2.0]]).is_none());
    // Both vertex orders give the same hit; the normal flips (eq. 6).
    let a = PreparedSimplex::<3>::new(&[[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]]).unwrap();
    let b = PreparedSimplex::<3>::new(&[[0., 0., 0.], [0., 1., 0.], [1., 0., 0.]]).unwrap();
    assert_eq!(a.normal(), [0., 0., 1.]);
    assert_eq!(b.normal(), [0., 0., -1.]);
    let ray = Ray {
        origin: [0.25, 0.25, 2.0],
        dir: [0.0, 0.0, -1.0],
    };
    let (ta, ba) = a.intersect(&ray, 0.0, f64::INFINITY).unwrap();
    let (tb, bb) = b.intersect(&ray, 0.0, f64::INFINITY).unwrap();
    assert_eq!((ta, tb), (2.0, 2.0));
    assert_eq!(ba, [0.5, 0.25, 0.25]);
    assert_eq!(bb, [0.5, 0.25, 0.25]);
    // The interval is open.
    assert!(a.intersect(&ray, 0.0, 2.0).is_none());
    assert!(a.intersect(&ray, 2.0, 3.0).is_none());
}

/// The test with rows rounded to f32 never contradicts the exact one: a lane it calls a hit is
/// an exact hit (inside, not parallel), one it calls a miss is an exact miss (or, once the
/// rounded rows decide, a hit whose rounded t is out of range), on rays aimed at the boundary
/// from ±10⁻⁹ to ±10⁻⁵ (barycentric), at slivers, at small simplices far from the origin and
/// nearly parallel; and it leaves few lanes unsure.
fn rounded_test_is_certified<const N: usize>() {
    use crate::accel::simplex::PreparedRay;
    let mut r = rng(1900 + N as u64);
    let (mut hits, mut misses, mut unsure, mut total) = (0, 0, 0, 0);
    let mut unsure_by_off = [0; 8];
    for case in 0..4000 {
        let far = if case % 3 == 0 { 1e3 } else { 0.0 };
        let size = [2.0, 1e-3, 1.0][case % 3];
        let mut pts = random_simplex::<N>(&mut r, &[far; N], size);
        if case % 5 == 0 {
            // A sliver: the last vertex nearly on the span of the others.
            let mid = plane_point(&mut r, &pts, 0.0, 1.0);
            pts[N - 1] = add_scaled(&mid, 1e-3, &crate::linalg::sub(&pts[N - 1], &mid));
        }
        let Some(ps) = PreparedSimplex::new(&pts) else {
            continue;
        };
        let rows = ps.rounded_rows();
        let origin = add_scaled(&pts[0], 3.0 * size, &random_unit::<N>(&mut r));
        // A point on the boundary pushed in or out by `off` (barycentric), or anywhere.
        let off = [0.0, 1e-9, -1e-9, 1e-7, -1e-7, 1e-5, -1e-5, 0.3][case % 8];
        let target = if case % 8 == 7 {
            plane_point(&mut r, &pts, -0.1, 1.0)
        } else {
            let mut w: [f64; N] = std::array::from_fn(|_| r.random_range(0.0..1.0));
            w[r.random_range(0..N)] = 0.0;
            let s: f64 = w.iter().sum();
            let mut w = w.map(|x| x / s);
            let k = w.iter().position(|&x| x == 0.0).unwrap();
            w[k] = off;
            w[(k + 1) % N] -= off;
            std::array::from_fn(|i| (0..N).map(|j| w[j] * pts[j][i]).sum())
        };
        let mut dir = crate::linalg::sub(&target, &origin);
        if case % 11 == 0 {
            // Nearly parallel to the hyperplane.
            let n = ps.normal();
            let along = crate::linalg::dot(&dir, &n);
            dir = add_scaled(&dir, -along * (1.0 - 1e-9), &n);
        }
        let ray = PreparedRay::new(&Ray { origin, dir });
        let (origin, dir) = (ray.o, ray.d);
        let (tmin, tmax) = [(0.0, f64::INFINITY), (0.0, 1.0), (1.0, 2.0)][case % 3];
        let got = PreparedSimplex::hit_rounded(&rows, &ps.origin(), &ray, tmin, tmax);
        let exact = ps.hit(&ray, tmin, tmax);
        let exact_inside = ps.hit(&ray, f64::NEG_INFINITY, f64::INFINITY);
        total += 1;
        if got.hit {
            hits += 1;
            assert!(exact_inside.is_some(), "N={N} case {case}: a false hit");
            // The rounded hit point lies within 2⁻²⁴·|X − x_0| of the exact hyperplane (along
            // the ray it may move further, by 1/cos of the incidence).
            let x = add_scaled(&origin, got.t, &dir);
            let q = crate::linalg::sub(&x, &ps.origin());
            let off = crate::linalg::dot(&ps.normal(), &q).abs();
            // (Plus the f64 rounding of the coordinates.)
            let bound = 1.2e-7 * crate::linalg::norm(&q) + 1e-14 * crate::linalg::norm(&x);
            assert!(off <= bound, "N={N} case {case}: {off} off the plane");
        } else if got.unsure {
            unsure_by_off[case % 8] += 1;
            // (Slivers and rays within 10⁻⁹ of parallel are unsure much further out.)
            if case % 8 == 7 && case % 5 != 0 && case % 11 != 0 {
                unsure += 1;
            }
        } else {
            misses += 1;
            let t_out = !(got.t > tmin && got.t < tmax);
            assert!(
                exact.is_none() || t_out,
                "N={N} case {case}: a false miss (off {off})"
            );
        }
    }
    // Away from the boundary (random targets) almost every lane is decided.
    assert!(
        hits > total / 40 && misses > total / 20 && unsure <= total / 200,
        "N={N}: {hits} hits, {misses} misses, {unsure} unsure of {total} ({unsure_by_off:?})"
    );
}

#[test]
fn accel_the_rounded_ray_test_never_contradicts_the_exact_one() {
    for_each_dim!(rounded_test_is_certified);
}
