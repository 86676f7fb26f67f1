use super::*;
use crate::testutil::rng;
use rand::Rng;
use std::f64::consts::PI;

/// ½∫ f(φ) cos φ dφ over (−π/2, π/2) by a fine midpoint rule: the mean over a tube's width.
fn tube_mean(f: impl Fn(f64) -> f64) -> f64 {
    let n = 200_000;
    let h = PI / n as f64;
    (0..n)
        .map(|k| {
            let phi = -PI / 2.0 + (k as f64 + 0.5) * h;
            f(phi) * phi.cos()
        })
        .sum::<f64>()
        * h
        / 2.0
}

#[test]
fn the_diffuse_limit_is_the_mean_of_lambert_over_the_tube() {
    let mut rng = rng(7);
    for case in 0..200 {
        let (l_e, l_w) = match case {
            0 => (1.0, 0.0),
            1 => (-1.0, 0.0),
            2 => (0.0, 1.0),
            _ => (2.0 * rng.random::<f64>() - 1.0, rng.random::<f64>()),
        };
        let want = tube_mean(|phi| (phi.cos() * l_e + phi.sin() * l_w).max(0.0));
        let got = tube_diffuse(l_e, l_w);
        assert!(
            (got - want).abs() < 1e-8,
            "l = ({l_e}, {l_w}): {got} vs {want}"
        );
    }
    // The closed forms: π/4 for a light behind the eye, 0 straight behind the tube.
    assert!((tube_diffuse(1.0, 0.0) - PI / 4.0).abs() < 1e-15);
    assert_eq!(tube_diffuse(-1.0, 0.0), 0.0);
}

#[test]
fn the_specular_limit_is_the_mean_of_blinn_phong_over_the_tube() {
    let mut rng = rng(11);
    for s in [0.0, 1.0, 4.5, 32.0, 128.0] {
        for _ in 0..40 {
            let a = PI * rng.random::<f64>();
            let r = 0.2 + 0.8 * rng.random::<f64>();
            let (h_e, h_w) = (r * a.cos(), r * a.sin());
            let want = tube_mean(|phi| (phi.cos() * h_e + phi.sin() * h_w).max(0.0).powf(s));
            let got = tube_specular(h_e, h_w, s);
            assert!(
                (got - want).abs() <= 2e-3 * want.max(1e-3),
                "s = {s}, h = ({h_e}, {h_w}): {got} vs {want}"
            );
        }
    }
}
