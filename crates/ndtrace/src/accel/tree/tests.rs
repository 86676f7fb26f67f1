use super::*;
use crate::accel::tests::*;

#[test]
fn f32_up_is_the_smallest_f32_not_below() {
    let mut r = rng(77);
    let tiny = f64::from(f32::from_bits(1));
    let big = f64::from(f32::MAX) * (1.0 + 1e-12);
    let mut xs = vec![
        0.0,
        -0.0,
        1e-50,
        -1e-50,
        0.5 * tiny,
        -0.5 * tiny,
        1.0,
        -1.0,
        big,
        -big,
        1e300,
        -1e300,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    for _ in 0..20000 {
        let x = r.random_range(-1.0..1.0) * 2f64.powi(r.random_range(-160..160));
        xs.extend([x, f64::from(x as f32)]);
    }
    for x in xs {
        let f = x as f32;
        let want = if (f as f64) < x { f.next_up() } else { f };
        assert_eq!(f32_up(x).to_bits(), want.to_bits(), "x = {x:e}");
        assert!(f64::from(f32_up(x)) >= x, "x = {x:e}");
    }
}
