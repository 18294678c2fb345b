//! The memory budget: every allocation whose size comes from input — an image's dimensions, a
//! resolution, an instance count, a channel count — is estimated first and refused past a limit,
//! with an error that says what was asked and how much it needs.
//!
//! The limit is process-wide. By default it is half of the smallest of the machine's physical
//! memory, the control group's `memory.max` and the process's address-space limit (Linux; 8 GiB
//! where none can be read). [`set_limit`] changes it (`trompe --memory-limit`).
//!
//! One account, process-wide, holds what is alive: every image ([`crate::frame::Image`]), every
//! BVH ([`crate::trace::Bvh`]), the rasterizer's kept set-up and a curved camera's tessellation
//! draw their bytes from it when made and return them when dropped ([`Held`]). A check refuses
//! a new request when it and what is held together pass the limit, so six atlases, sixteen
//! textures or two compared images are refused by their sum, each part fitting alone. A mesh is
//! checked when it is loaded but not held.
//!
//! Invariant: a check is made before the allocation it guards, so a refusal costs nothing.

use std::sync::atomic::{AtomicU64, Ordering};
use thiserror::Error;

/// The limit used where the machine's memory cannot be read.
const FALLBACK_BYTES: u64 = 8 << 30;

/// 0 until set or first read.
static LIMIT: AtomicU64 = AtomicU64::new(0);

/// An allocation refused by the budget.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
#[error(
    "{what} needs {} but the memory limit is {} (raise it with --memory-limit, or \
     trompe::memory::set_limit)",
    Bytes(*needed),
    Bytes(*limit)
)]
pub struct OverBudget {
    /// What was asked for, in the user's words ("a 8192 × 8192 render", "texture 3").
    pub what: String,
    /// Bytes it needs (an estimate from its dimensions).
    pub needed: u64,
    /// The limit in force.
    pub limit: u64,
}

/// The limit in force, in bytes.
pub fn limit() -> u64 {
    match LIMIT.load(Ordering::Relaxed) {
        0 => {
            let default = default_limit();
            // Another thread may have set a limit meanwhile: keep theirs.
            match LIMIT.compare_exchange(0, default, Ordering::Relaxed, Ordering::Relaxed) {
                Ok(_) => default,
                Err(set) => set,
            }
        }
        set => set,
    }
}

/// Sets the process-wide limit (at least one byte).
pub fn set_limit(bytes: u64) {
    LIMIT.store(bytes.max(1), Ordering::Relaxed);
}

/// Bytes the account holds now.
static HELD: AtomicU64 = AtomicU64::new(0);

/// Bytes of input-sized memory alive in the process now (images, BVHs, the rasterizer's kept
/// set-up, tessellations).
pub fn held() -> u64 {
    HELD.load(Ordering::Relaxed)
}

/// A share of the account: its bytes count as held until it is dropped. A clone holds its
/// bytes again (a cloned image is a second allocation).
#[derive(Debug)]
pub struct Held(u64);

impl Held {
    /// Counts `bytes` as held (the allocation is made or checked already).
    pub fn new(bytes: u64) -> Held {
        HELD.fetch_add(bytes, Ordering::Relaxed);
        Held(bytes)
    }

    /// The bytes it holds.
    pub fn bytes(&self) -> u64 {
        self.0
    }

    /// Holds `bytes` from now on instead (working memory kept between uses, grown or shrunk).
    pub fn set(&mut self, bytes: u64) {
        HELD.fetch_add(bytes, Ordering::Relaxed);
        HELD.fetch_sub(self.0, Ordering::Relaxed);
        self.0 = bytes;
    }
}

impl Default for Held {
    /// Nothing held.
    fn default() -> Held {
        Held::new(0)
    }
}

impl Clone for Held {
    fn clone(&self) -> Held {
        Held::new(self.0)
    }
}

impl Drop for Held {
    fn drop(&mut self) {
        HELD.fetch_sub(self.0, Ordering::Relaxed);
    }
}

/// Refuses `needed` bytes for `what` when they and what the process holds pass the limit in
/// force; the error names what is held.
pub fn check(what: impl FnOnce() -> String, needed: u64) -> Result<(), OverBudget> {
    let held = held();
    check_against(
        limit(),
        || {
            if held == 0 {
                what()
            } else {
                format!("{} (on top of {} already held)", what(), Bytes(held))
            }
        },
        held.saturating_add(needed),
    )
}

/// Refuses `needed` bytes for `what` past `limit`.
pub fn check_against(
    limit: u64,
    what: impl FnOnce() -> String,
    needed: u64,
) -> Result<(), OverBudget> {
    if needed > limit {
        return Err(OverBudget {
            what: what(),
            needed,
            limit,
        });
    }
    Ok(())
}

/// `count × each` bytes, saturating (a saturated product is always over any budget).
pub fn times(count: u64, each: u64) -> u64 {
    count.saturating_mul(each)
}

/// Half of the smallest memory bound the process lives under.
pub fn default_limit() -> u64 {
    let bounds = [physical_memory(), cgroup_limit(), address_space_limit()];
    bounds
        .into_iter()
        .flatten()
        .min()
        .map_or(FALLBACK_BYTES, |b| (b / 2).max(1))
}

fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

fn cgroup_limit() -> Option<u64> {
    let text = std::fs::read_to_string("/sys/fs/cgroup/memory.max").ok()?;
    text.trim().parse().ok()
}

fn address_space_limit() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = text.lines().find(|l| l.starts_with("Max address space"))?;
    // "Max address space   <soft>   <hard>   bytes"; "unlimited" parses as no bound.
    line.split_whitespace().nth(3)?.parse().ok()
}

/// Parses a size as a user writes it: `4096`, `512M`, `2G`, `1.5GiB`, `64k` (binary multiples).
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let value: f64 = number
        .parse()
        .map_err(|_| format!("`{text}` is not a size (try 512M or 2G)"))?;
    let scale: u64 = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1,
        "k" | "kb" | "kib" => 1 << 10,
        "m" | "mb" | "mib" => 1 << 20,
        "g" | "gb" | "gib" => 1 << 30,
        "t" | "tb" | "tib" => 1 << 40,
        other => return Err(format!("unknown size unit `{other}` (use K, M, G or T)")),
    };
    let bytes = value * scale as f64;
    if !bytes.is_finite() || bytes < 1.0 || bytes > u64::MAX as f64 {
        return Err(format!("`{text}` is not a usable size"));
    }
    Ok(bytes as u64)
}

/// A byte count printed for people: `512 B`, `3.2 MiB`, `4.0 GiB`.
#[derive(Clone, Copy, Debug)]
pub struct Bytes(pub u64);

impl std::fmt::Display for Bytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        const UNITS: [&str; 5] = ["KiB", "MiB", "GiB", "TiB", "PiB"];
        if self.0 < 1024 {
            return write!(f, "{} B", self.0);
        }
        let mut value = self.0 as f64 / 1024.0;
        let mut unit = 0;
        while value >= 1024.0 && unit + 1 < UNITS.len() {
            value /= 1024.0;
            unit += 1;
        }
        write!(f, "{value:.1} {}", UNITS[unit])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_units() {
        assert_eq!(parse_size("4096"), Ok(4096));
        assert_eq!(parse_size("512M"), Ok(512 << 20));
        assert_eq!(parse_size("2G"), Ok(2 << 30));
        assert_eq!(parse_size("1.5GiB"), Ok(3 << 29));
        assert_eq!(parse_size("64k"), Ok(64 << 10));
        assert!(parse_size("lots").is_err());
        assert!(parse_size("5Q").is_err());
        assert!(parse_size("0").is_err());
        assert!(parse_size("nanG").is_err());
    }

    #[test]
    fn the_check_refuses_past_the_limit_and_names_the_request() {
        assert!(check_against(100, || "x".into(), 100).is_ok());
        let e = check_against(100, || "a 8192 × 8192 render".into(), 101).unwrap_err();
        assert_eq!(e.needed, 101);
        let text = e.to_string();
        assert!(text.contains("a 8192 × 8192 render") && text.contains("--memory-limit"));
        assert_eq!(times(u64::MAX, 2), u64::MAX);
        // What is held counts: a request that fits alone is refused on top of it.
        let before = held();
        let a = Held::new(1 << 20);
        assert_eq!(held() - before, 1 << 20);
        let b = a.clone();
        assert_eq!(held() - before, 2 << 20);
        drop((a, b));
    }

    #[test]
    fn the_default_is_a_positive_fraction_of_the_machine() {
        let d = default_limit();
        assert!(d > 0);
        if let Some(p) = physical_memory() {
            assert!(d <= p / 2);
        }
    }

    #[test]
    fn bytes_print_for_people() {
        assert_eq!(Bytes(512).to_string(), "512 B");
        assert_eq!(Bytes(3 << 20).to_string(), "3.0 MiB");
        assert_eq!(Bytes(4 << 30).to_string(), "4.0 GiB");
    }
}
