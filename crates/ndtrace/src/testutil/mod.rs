//! What the unit tests share: seeded random inputs, the per-dimension driver
//! [`for_each_dim!`], and test oracles ([`exact`]).

pub mod exact;

use crate::linalg::{det, dot, norm, scale, sub, Matrix, Vector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub type TestRng = ChaCha8Rng;

/// A deterministic generator for a test.
pub fn rng(seed: u64) -> TestRng {
    ChaCha8Rng::seed_from_u64(0x6e64_7472_6163_6500 ^ seed)
}

/// A vector with entries uniform in [−s, s].
pub fn random_vector<const N: usize>(r: &mut TestRng, s: f64) -> Vector<N> {
    std::array::from_fn(|_| r.random_range(-s..=s))
}

/// A matrix with entries uniform in [−1, 1].
pub fn random_matrix<const N: usize>(r: &mut TestRng) -> Matrix<N> {
    std::array::from_fn(|_| random_vector(r, 1.0))
}

/// `count` points with coordinates uniform in [−s, s].
pub fn random_points<const N: usize>(r: &mut TestRng, count: usize, s: f64) -> Vec<Vector<N>> {
    (0..count).map(|_| random_vector(r, s)).collect()
}

/// `x·e_k` in R^N as a TOML array (scene texts of the tests).
pub fn unit_toml<const N: usize>(k: usize, x: f64) -> String {
    let v: Vec<String> = (0..N)
        .map(|i| {
            if i == k {
                format!("{x:?}")
            } else {
                "0.0".into()
            }
        })
        .collect();
    format!("[{}]", v.join(", "))
}

/// The message of the error that loading the scene text `text` (as `scene.toml`) gives; panics
/// when it loads.
pub fn load_error(text: &str) -> String {
    match crate::scene::load_toml_str(text, "scene.toml", None) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("expected an error for:\n{text}"),
    }
}

/// A random rotation (orthonormal, det +1) from Gram–Schmidt on random rows.
pub fn random_rotation<const N: usize>(r: &mut TestRng) -> Matrix<N> {
    loop {
        let mut m = random_matrix::<N>(r);
        let mut ok = true;
        for i in 0..N {
            for j in 0..i {
                let p = dot(&m[i], &m[j]);
                m[i] = sub(&m[i], &scale(&m[j], p));
            }
            let l = norm(&m[i]);
            if l < 1e-3 {
                ok = false;
                break;
            }
            m[i] = scale(&m[i], 1.0 / l);
        }
        if ok {
            if det(&m) < 0.0 {
                m[0] = scale(&m[0], -1.0);
            }
            return m;
        }
    }
}

/// A random reflection-containing orthogonal matrix (det −1).
pub fn random_reflection<const N: usize>(r: &mut TestRng) -> Matrix<N> {
    let mut m = random_rotation::<N>(r);
    m[N - 1] = scale(&m[N - 1], -1.0);
    m
}

/// Calls the generic function `$f::<N>()` for every supported N, through [`crate::with_dim!`].
macro_rules! for_each_dim {
    ($f:ident) => {
        for d in $crate::MIN_DIM..=$crate::MAX_DIM {
            $crate::with_dim!(d, N => $f::<N>()).unwrap();
        }
    };
}
pub(crate) use for_each_dim;
