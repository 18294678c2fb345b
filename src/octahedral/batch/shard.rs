//! Which part of a batch one machine bakes: shard `K` of `N` of the sorted inputs, given on the
//! command line or read from a job scheduler's variables — Slurm's array (`SLURM_ARRAY_TASK_ID`,
//! `SLURM_ARRAY_TASK_MIN`, `SLURM_ARRAY_TASK_STEP`, `SLURM_ARRAY_TASK_COUNT`) or a Kubernetes
//! Indexed Job (`JOB_COMPLETION_INDEX`, 0-based, with the count given).
//!
//! Invariants: shards are 1-based (`1 ≤ K ≤ N`); the inputs of a shard depend only on the sorted
//! list of every input, so every machine computes the same partition.

use super::BatchError;

/// Which part of the inputs one machine bakes: shard `index` (1-based) of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    /// 1 ..= count.
    pub index: u32,
    /// Shards in all.
    pub count: u32,
}

impl Shard {
    /// The whole batch: shard 1 of 1.
    pub const ALL: Shard = Shard { index: 1, count: 1 };

    /// Whether the `i`-th (0-based) of the sorted inputs is in this shard.
    pub fn holds(self, i: usize) -> bool {
        i as u64 % u64::from(self.count) == u64::from(self.index - 1)
    }

    /// The shard a job scheduler gave this task, from its variables (`var` looks one up):
    /// a Slurm array task's, or a Kubernetes Indexed Job's completion index (0-based) with
    /// `count` shards. A `count` given with Slurm's variables must be the array's.
    ///
    /// # Errors
    /// No scheduler's variables, a value that is not a number, an index past the count, an
    /// array whose task ids do not step evenly, or a Kubernetes index without a count.
    pub fn from_scheduler(
        var: impl Fn(&str) -> Option<String>,
        count: Option<u32>,
    ) -> Result<Shard, BatchError> {
        let number = |name: &'static str| -> Result<Option<u64>, BatchError> {
            match var(name) {
                None => Ok(None),
                Some(v) => v
                    .trim()
                    .parse::<u64>()
                    .map(Some)
                    .map_err(|_| BatchError::Scheduler {
                        reason: format!("{name}={v:?} is not a whole number"),
                    }),
            }
        };
        let refused = |reason: String| BatchError::Scheduler { reason };
        if let Some(id) = number("SLURM_ARRAY_TASK_ID")? {
            let min = number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let step = number("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
            let tasks = number("SLURM_ARRAY_TASK_COUNT")?.ok_or_else(|| {
                refused("SLURM_ARRAY_TASK_ID is set but not SLURM_ARRAY_TASK_COUNT".into())
            })?;
            let offset = id
                .checked_sub(min)
                .filter(|o| o % step == 0)
                .ok_or_else(|| {
                    refused(format!(
                        "task {id} is not on the array's steps (min {min}, step {step})"
                    ))
                })?;
            let index = offset / step + 1;
            if let Some(c) = count
                && u64::from(c) != tasks
            {
                return Err(refused(format!(
                    "--shard auto/{c}, but the Slurm array has {tasks} tasks"
                )));
            }
            return Self::checked(index, tasks, "Slurm array task");
        }
        if let Some(i) = number("JOB_COMPLETION_INDEX")? {
            let count = count.ok_or_else(|| {
                refused(
                    "JOB_COMPLETION_INDEX is set, but Kubernetes gives no count: say it with \
                     --shard auto/N (N: the Job's completions)"
                        .into(),
                )
            })?;
            return Self::checked(i + 1, u64::from(count), "Kubernetes completion index");
        }
        Err(refused(
            "--shard auto: neither SLURM_ARRAY_TASK_ID (a Slurm array job) nor \
             JOB_COMPLETION_INDEX (a Kubernetes Indexed Job) is set"
                .into(),
        ))
    }

    fn checked(index: u64, count: u64, what: &str) -> Result<Shard, BatchError> {
        match (u32::try_from(index), u32::try_from(count)) {
            (Ok(index), Ok(count)) if count > 0 && (1..=count).contains(&index) => {
                Ok(Shard { index, count })
            }
            _ => Err(BatchError::Scheduler {
                reason: format!("{what}: shard {index} of {count} (need 1 ≤ K ≤ N)"),
            }),
        }
    }
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (k, n) = s
            .split_once('/')
            .ok_or_else(|| format!("{s:?}: expected K/N, e.g. 2/8"))?;
        let (k, n): (u32, u32) = (
            k.trim()
                .parse()
                .map_err(|_| format!("{s:?}: K is not a number"))?,
            n.trim()
                .parse()
                .map_err(|_| format!("{s:?}: N is not a number"))?,
        );
        if n == 0 || k == 0 || k > n {
            return Err(format!("{s:?}: need 1 ≤ K ≤ N"));
        }
        Ok(Shard { index: k, count: n })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn vars(pairs: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
        let map: HashMap<String, String> = pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        move |k| map.get(k).cloned()
    }

    #[test]
    fn a_scheduler_names_the_shard() {
        // Slurm: --array=0-3 (4 tasks), task 2 is shard 3 of 4.
        let slurm = vars(&[
            ("SLURM_ARRAY_TASK_ID", "2"),
            ("SLURM_ARRAY_TASK_MIN", "0"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert_eq!(
            Shard::from_scheduler(&slurm, None).unwrap(),
            Shard { index: 3, count: 4 }
        );
        // --array=1-4 counts from 1; --array=10-40:10 steps by 10.
        let from_one = vars(&[
            ("SLURM_ARRAY_TASK_ID", "1"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert_eq!(
            Shard::from_scheduler(&from_one, None).unwrap(),
            Shard { index: 1, count: 4 }
        );
        let stepped = vars(&[
            ("SLURM_ARRAY_TASK_ID", "30"),
            ("SLURM_ARRAY_TASK_MIN", "10"),
            ("SLURM_ARRAY_TASK_STEP", "10"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert_eq!(
            Shard::from_scheduler(&stepped, None).unwrap(),
            Shard { index: 3, count: 4 }
        );
        // Kubernetes: the index is 0-based and the count is given.
        let k8s = vars(&[("JOB_COMPLETION_INDEX", "0")]);
        assert_eq!(
            Shard::from_scheduler(&k8s, Some(5)).unwrap(),
            Shard { index: 1, count: 5 }
        );
        let last = vars(&[("JOB_COMPLETION_INDEX", "4")]);
        assert_eq!(
            Shard::from_scheduler(&last, Some(5)).unwrap(),
            Shard { index: 5, count: 5 }
        );
        // Refusals, each with its reason.
        for (v, count, says) in [
            (vars(&[]), None, "neither"),
            (vars(&[("JOB_COMPLETION_INDEX", "0")]), None, "auto/N"),
            (vars(&[("JOB_COMPLETION_INDEX", "5")]), Some(5), "6 of 5"),
            (
                vars(&[("JOB_COMPLETION_INDEX", "-1")]),
                Some(5),
                "whole number",
            ),
            (
                vars(&[("SLURM_ARRAY_TASK_ID", "3")]),
                None,
                "SLURM_ARRAY_TASK_COUNT",
            ),
            (
                vars(&[
                    ("SLURM_ARRAY_TASK_ID", "2"),
                    ("SLURM_ARRAY_TASK_COUNT", "4"),
                ]),
                Some(3),
                "4 tasks",
            ),
            (
                vars(&[
                    ("SLURM_ARRAY_TASK_ID", "15"),
                    ("SLURM_ARRAY_TASK_MIN", "10"),
                    ("SLURM_ARRAY_TASK_STEP", "10"),
                    ("SLURM_ARRAY_TASK_COUNT", "4"),
                ]),
                None,
                "steps",
            ),
        ] {
            let e = Shard::from_scheduler(&v, count).unwrap_err().to_string();
            assert!(e.contains(says), "{e}");
        }
    }
}
