//! `--shard I/N`: the I-th of N deterministic slices of a list (of a sweep's runs, of script
//! tests). Counted from 1, as `cargo nextest --partition count:I/N`: run k (counted from 0 in
//! the list's order) belongs to shard (k mod N) + 1, so shards stay balanced whatever the order.

use super::SweepError;
use std::str::FromStr;

/// One slice of N: `index` is 1..=`count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// Which slice, from 1.
    pub index: usize,
    /// How many slices.
    pub count: usize,
}

impl Shard {
    /// True when item `k` (counted from 0) belongs to this shard.
    pub fn contains(&self, k: usize) -> bool {
        k % self.count == self.index - 1
    }

    /// The items of this shard, in order.
    pub fn select<T>(&self, items: impl IntoIterator<Item = T>) -> Vec<T> {
        items
            .into_iter()
            .enumerate()
            .filter(|(k, _)| self.contains(*k))
            .map(|(_, t)| t)
            .collect()
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = SweepError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = |reason: String| SweepError::Shard {
            spec: s.to_string(),
            reason,
        };
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| bad("write I/N, e.g. --shard 1/4 (shards count from 1)".into()))?;
        let number = |t: &str, what: &str| {
            t.trim().parse::<usize>().map_err(|_| {
                bad(format!(
                    "{what} '{t}' is not a whole number; write I/N, e.g. 1/4"
                ))
            })
        };
        let (index, count) = (number(i, "I")?, number(n, "N")?);
        if count == 0 {
            return Err(bad("N must be at least 1".into()));
        }
        if index == 0 || index > count {
            return Err(bad(format!(
                "I must be between 1 and {count} (shards count from 1, as nextest's --partition)"
            )));
        }
        Ok(Shard { index, count })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cover_every_item_once() {
        for count in 1..6 {
            let mut seen = vec![0; 17];
            for index in 1..=count {
                for k in (Shard { index, count }).select(0..17) {
                    seen[k] += 1;
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "{count}: {seen:?}");
        }
    }

    #[test]
    fn bad_specs_say_what_to_write() {
        for bad in ["0/2", "3/2", "1/0", "x/2", "2", "1/-1"] {
            let e = bad.parse::<Shard>().expect_err(bad).to_string();
            assert!(e.starts_with(&format!("--shard {bad}:")), "{e}");
        }
        assert_eq!(
            "2/3".parse::<Shard>().ok(),
            Some(Shard { index: 2, count: 3 })
        );
    }
}
