use super::*;

#[test]
fn latin_hypercube_offsets_stratify_every_axis() {
    let mut rng = SplitMix::new(7, 3);
    let mut out = vec![];
    sample_offsets(16, 3, &mut rng, &mut out);
    for k in 0..3 {
        let mut strata: Vec<usize> = (0..16).map(|j| (out[j * 3 + k] * 16.0) as usize).collect();
        strata.sort();
        assert_eq!(strata, (0..16).collect::<Vec<_>>());
    }
    sample_offsets(1, 3, &mut rng, &mut out);
    assert_eq!(out, vec![0.5; 3]);
}
