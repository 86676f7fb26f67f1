//! The memory guard: what this process may still allocate, and a check that refuses, with one
//! line saying what and how much, a request that would not fit instead of letting the
//! allocator abort the process (an abort kills a Python interpreter and its notebook kernel).
//!
//! The limit is the smallest of
//! - the system's `MemAvailable` (`/proc/meminfo`),
//! - the address-space and data-segment limits (`RLIMIT_AS`, `ulimit -v`; `RLIMIT_DATA`) less
//!   what the process already maps (`VmSize`, `VmData` in `/proc/self/status`),
//! - the cgroup's `memory.max` less its `memory.current` (cgroup v2; v1's
//!   `memory.limit_in_bytes` less `memory.usage_in_bytes`), for containers and systemd slices,
//! - a cap set with [`set_cap`] or the environment variable `NDTRACE_MEMORY_LIMIT` (bytes, or
//!   with a `K`/`M`/`G` suffix): for tests and fuzzing.
//!
//! A request is refused when it asks for more than half of that ([`SPARE_FRACTION`]): the
//! estimate counts the main arrays only, and the process needs room for everything else.

use std::sync::atomic::{AtomicU64, Ordering};

/// The share of the available memory one request may take.
pub const SPARE_FRACTION: f64 = 0.5;

/// Where the binding limit comes from, for the refusal message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// `MemAvailable` in `/proc/meminfo`.
    System,
    /// `RLIMIT_AS` (`ulimit -v`).
    AddressSpace,
    /// `RLIMIT_DATA` (`ulimit -d`).
    Data,
    /// The cgroup's memory limit.
    Cgroup,
    /// [`set_cap`] or `NDTRACE_MEMORY_LIMIT`.
    Cap,
}

impl Source {
    fn describe(self) -> &'static str {
        match self {
            Source::System => "of free system memory",
            Source::AddressSpace => "left under the address-space limit RLIMIT_AS (ulimit -v)",
            Source::Data => "left under the data-segment limit RLIMIT_DATA (ulimit -d)",
            Source::Cgroup => "left under the cgroup's memory limit (memory.max)",
            Source::Cap => "allowed by NDTRACE_MEMORY_LIMIT",
        }
    }
}

/// 0 = no cap set by [`set_cap`].
static CAP: AtomicU64 = AtomicU64::new(0);

/// Caps the memory the guard lets this process use (`None` removes the cap; the environment
/// variable `NDTRACE_MEMORY_LIMIT` still applies).
pub fn set_cap(bytes: Option<u64>) {
    CAP.store(bytes.map_or(0, |b| b.max(1)), Ordering::Relaxed);
}

fn env_cap() -> Option<u64> {
    let text = std::env::var("NDTRACE_MEMORY_LIMIT").ok()?;
    let t = text.trim();
    let (num, unit) = match t.char_indices().last()? {
        (i, c) if c.is_ascii_alphabetic() => (&t[..i], c.to_ascii_uppercase()),
        _ => (t, 'B'),
    };
    let shift = match unit {
        'B' => 0,
        'K' => 10,
        'M' => 20,
        'G' => 30,
        'T' => 40,
        _ => return None,
    };
    num.trim().parse::<u64>().ok()?.checked_mul(1 << shift)
}

fn status_kib(status: &str, key: &str) -> Option<u64> {
    status
        .lines()
        .find(|l| l.starts_with(key))?
        .split_whitespace()
        .nth(1)?
        .parse()
        .ok()
}

/// The soft limit of the `/proc/self/limits` row `name` (None when unlimited).
fn soft_limit(limits: &str, name: &str) -> Option<u64> {
    limits
        .lines()
        .find(|l| l.starts_with(name))?
        .get(name.len()..)?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

fn read_u64(path: &str) -> Option<u64> {
    std::fs::read_to_string(path).ok()?.trim().parse().ok()
}

/// The tightest cgroup limit left over this process's cgroup and its ancestors.
fn cgroup_left() -> Option<u64> {
    let groups = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let mut best: Option<u64> = None;
    let mut consider = |max: Option<u64>, used: Option<u64>| {
        if let Some(max) = max {
            let left = max.saturating_sub(used.unwrap_or(0));
            best = Some(best.map_or(left, |b| b.min(left)));
        }
    };
    for line in groups.lines() {
        let mut parts = line.splitn(3, ':');
        let (Some(_), Some(controllers), Some(path)) = (parts.next(), parts.next(), parts.next())
        else {
            continue;
        };
        // v2 (one unified hierarchy, "0::/path") and v1's memory controller.
        let (root, max_file, used_file) = if controllers.is_empty() {
            ("/sys/fs/cgroup", "memory.max", "memory.current")
        } else if controllers.split(',').any(|c| c == "memory") {
            (
                "/sys/fs/cgroup/memory",
                "memory.limit_in_bytes",
                "memory.usage_in_bytes",
            )
        } else {
            continue;
        };
        let mut dir = std::path::PathBuf::from(format!("{root}{path}"));
        loop {
            let f = |name: &str| read_u64(&dir.join(name).to_string_lossy());
            consider(f(max_file), f(used_file));
            if dir.as_os_str().len() <= root.len() || !dir.pop() {
                break;
            }
        }
    }
    best
}

/// The memory this process can still allocate, in bytes, and where that limit comes from.
pub fn available() -> (u64, Source) {
    let mut best = (u64::MAX, Source::System);
    let mut consider = |v: Option<u64>, s: Source| {
        if let Some(v) = v {
            if v < best.0 {
                best = (v, s);
            }
        }
    };
    let meminfo = std::fs::read_to_string("/proc/meminfo").unwrap_or_default();
    consider(
        status_kib(&meminfo, "MemAvailable:").map(|k| k.saturating_mul(1024)),
        Source::System,
    );
    let limits = std::fs::read_to_string("/proc/self/limits").unwrap_or_default();
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let used = |key| status_kib(&status, key).unwrap_or(0).saturating_mul(1024);
    consider(
        soft_limit(&limits, "Max address space").map(|l| l.saturating_sub(used("VmSize:"))),
        Source::AddressSpace,
    );
    consider(
        soft_limit(&limits, "Max data size").map(|l| l.saturating_sub(used("VmData:"))),
        Source::Data,
    );
    consider(cgroup_left(), Source::Cgroup);
    let cap = CAP.load(Ordering::Relaxed);
    consider((cap > 0).then_some(cap).or_else(env_cap), Source::Cap);
    if best.0 == u64::MAX {
        // Not Linux: assume a workstation.
        best.0 = 16 << 30;
    }
    best
}

/// A byte count for people: "1.5 GiB".
pub fn human_bytes(b: f64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB", "ZiB", "YiB"];
    let mut v = b;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    if v >= 1024.0 {
        format!("{b:.3e} B")
    } else {
        format!("{v:.1} {}", units[u])
    }
}

/// Refuses `bytes` (an estimate; f64 so that any product of counts fits) for `what` ("a
/// retina of 8000000 cells") when it is more than the process can spare: the error is one
/// line, "`what` needs about 3.0 GiB of memory, more than this process can spare (600.0 MiB:
/// half of the 1.2 GiB of free system memory)"; the caller adds where.
pub fn check(bytes: f64, what: &str) -> Result<(), String> {
    let (avail, source) = available();
    let spare = avail as f64 * SPARE_FRACTION;
    if bytes.is_finite() && bytes <= spare {
        return Ok(());
    }
    Err(format!(
        "{what} needs about {} of memory, more than this process can spare ({}: half of the {} {})",
        human_bytes(bytes),
        human_bytes(spare),
        human_bytes(avail as f64),
        source.describe()
    ))
}

/// `a · b · …` of element counts, None on overflow of usize.
pub fn product(counts: &[usize]) -> Option<usize> {
    counts.iter().try_fold(1usize, |p, &c| p.checked_mul(c))
}

#[cfg(test)]
mod tests;
