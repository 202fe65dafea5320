//! `--shard K/N`: a deterministic share of an experiment's tasks, so that N machines
//! (or the N tasks of a job array) split one run without talking to each other.

/// A deterministic share of an experiment's tasks: shard `index` of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    /// Environment variables a job scheduler sets to the index of an array task.
    pub const INDEX_VARIABLES: [&str; 2] = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"];

    /// Reads `K/N`, or `N` with K from [`Self::INDEX_VARIABLES`] looked up in `env`.
    pub fn parse(text: &str, env: impl Fn(&str) -> Option<String>) -> Result<Shard, String> {
        let number = |part: &str, what: &str| {
            part.trim()
                .parse::<usize>()
                .map_err(|error| match error.kind() {
                    std::num::IntErrorKind::PosOverflow => {
                        format!("--shard {text}: {what} {part} is too large")
                    }
                    _ => format!("--shard {text}: {what} {part:?} is not a whole number"),
                })
        };
        let (index, count) = match text.split_once('/') {
            Some((index, count)) => (number(index, "shard index")?, number(count, "shard count")?),
            None => {
                let count = number(text, "shard count")?;
                let (variable, value) = Self::INDEX_VARIABLES
                    .iter()
                    .find_map(|v| env(v).map(|value| (*v, value)))
                    .ok_or_else(|| {
                        format!(
                            "--shard {text}: no shard index: write K/{text}, or set {}",
                            Self::INDEX_VARIABLES.join(" or ")
                        )
                    })?;
                let index = value.trim().parse::<usize>().map_err(|_| {
                    format!("--shard {text}: {variable}={value:?} is not a whole number")
                })?;
                (index, count)
            }
        };
        if count == 0 {
            return Err(format!(
                "--shard {text}: N is the number of shards, at least 1"
            ));
        }
        if index >= count {
            return Err(format!(
                "--shard {text}: shard {index} of {count} does not exist: K runs from 0 to N-1"
            ));
        }
        Ok(Shard { index, count })
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

    #[test]
    fn shards_come_from_the_argument_or_the_scheduler() {
        let none = |_: &str| None;
        assert_eq!(Shard::parse("2/3", none), Ok(Shard { index: 2, count: 3 }));
        let slurm = |v: &str| (v == "SLURM_ARRAY_TASK_ID").then(|| "1".to_string());
        assert_eq!(Shard::parse("4", slurm), Ok(Shard { index: 1, count: 4 }));
        let kubernetes = |v: &str| (v == "JOB_COMPLETION_INDEX").then(|| "0".to_string());
        assert_eq!(
            Shard::parse("2", kubernetes),
            Ok(Shard { index: 0, count: 2 })
        );
        assert_eq!(
            Shard::parse("3/3", none).unwrap_err(),
            "--shard 3/3: shard 3 of 3 does not exist: K runs from 0 to N-1"
        );
        assert_eq!(
            Shard::parse("0/0", none).unwrap_err(),
            "--shard 0/0: N is the number of shards, at least 1"
        );
        assert_eq!(
            Shard::parse("4", none).unwrap_err(),
            "--shard 4: no shard index: write K/4, or set SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX"
        );
        assert_eq!(
            Shard::parse("0/99999999999999999999", none).unwrap_err(),
            "--shard 0/99999999999999999999: shard count 99999999999999999999 is too large"
        );
        assert!(
            Shard::parse("a/2", none)
                .unwrap_err()
                .contains("\"a\" is not a whole number")
        );
    }
}
