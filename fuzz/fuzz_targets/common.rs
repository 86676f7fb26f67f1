// Shared set-up of the targets: the memory guard capped far below libFuzzer's -rss_limit_mb /
// -malloc_limit_mb (2 GiB by default), so that a request the guard lets through but libFuzzer
// reports as out-of-memory is a finding, not noise.
pub fn init() {
    ndtrace::memory::set_cap(Some(1 << 30));
}
