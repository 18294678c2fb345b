//! What long work reports as it goes: progress in rows (the CLI draws it as a bar) and the named
//! durations of a job's steps. The lowest layer: every module may report through it.

use std::time::{Duration, Instant};

/// Progress of long work, reported in rows; the CLI shows it as a bar.
pub trait Progress: Sync {
    /// `rows` more rows are done.
    fn advance(&self, rows: u64);
}

impl Progress for () {
    fn advance(&self, _: u64) {}
}

/// Named wall-clock durations of the steps of one job, in order.
#[derive(Clone, Debug, Default)]
pub struct Timings(pub Vec<(&'static str, Duration)>);

/// A duration as JSON: its seconds (for `#[serde(serialize_with)]`).
pub fn serialize_seconds<S: serde::Serializer>(d: &Duration, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64(d.as_secs_f64())
}

/// As JSON: each step's milliseconds, in order (`{"bake": 12.5, …}`).
impl serde::Serialize for Timings {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (name, d) in &self.0 {
            map.serialize_entry(name, &(d.as_secs_f64() * 1e3))?;
        }
        map.end()
    }
}

impl Timings {
    /// Runs `f`, recording its duration under `name`.
    pub fn time<T>(&mut self, name: &'static str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        self.0.push((name, start.elapsed()));
        out
    }
}
