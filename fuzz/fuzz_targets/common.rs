// Shared set-up of the targets: the memory guard capped far below libFuzzer's -rss_limit_mb /
// -malloc_limit_mb (2 GiB by default), so that a request the guard lets through but libFuzzer
// reports as out-of-memory is a finding, not noise.
#[allow(dead_code)]
pub fn init() {
    ndtrace::memory::set_cap(Some(1 << 30));
}

/// The scene target's cap, 64 MiB: the guard then also bounds the work one input can ask for
/// (a BVH of about 280,000 simplices, a retina of a few million cells), so that a slow but
/// legitimate scene (a sphere of many subdivisions, a huge retina) is refused at once instead of
/// reaching libFuzzer's `-timeout` as a false finding.
#[allow(dead_code)]
pub fn init_scene() {
    ndtrace::memory::set_cap(Some(64 << 20));
}
