//! Where a cell's rays cross it: its centre for one sample per cell; otherwise a seeded,
//! stratified jitter that depends only on the seed and the cell index (so not on the thread
//! that traces the cell).

/// SplitMix64: a small, fast, seedable generator for the sample jitter.
#[derive(Clone)]
pub(super) struct SplitMix(pub(super) u64);

impl SplitMix {
    /// The generator of cell `cell` for the scene's `seed`.
    pub(super) fn new(seed: u64, cell: u64) -> Self {
        let mut s = SplitMix(seed ^ 0x9e37_79b9_7f4a_7c15u64.wrapping_mul(cell.wrapping_add(1)));
        s.next();
        s
    }

    pub(super) fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in 0..n.
    fn below(&mut self, n: usize) -> usize {
        (((self.next() >> 32) * n as u64) >> 32) as usize
    }
}

/// Fractional sample positions inside a cell, `axes` per sample, into `out`: the centre for one
/// sample; otherwise stratified jitter (a Latin hypercube: along every retina axis each of the
/// S strata holds one sample).
pub(super) fn sample_offsets(samples: usize, axes: usize, rng: &mut SplitMix, out: &mut Vec<f64>) {
    out.clear();
    out.resize(samples * axes, 0.5);
    if samples == 1 {
        return;
    }
    let mut perm: Vec<usize> = (0..samples).collect();
    for k in 0..axes {
        for i in (1..samples).rev() {
            perm.swap(i, rng.below(i + 1));
        }
        for (j, &p) in perm.iter().enumerate() {
            out[j * axes + k] = (p as f64 + rng.unit()) / samples as f64;
        }
    }
}

#[cfg(test)]
mod tests;
