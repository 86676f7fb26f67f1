use super::*;

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
