//! The axes expanded into the ordered run list: the product of every axis, in a fixed order
//! (method, dt, n, steps, the constants by name, then seed varying fastest), so a sweep file
//! always gives the same list and the same shards.

use super::{RunParams, SweepFile};

impl SweepFile {
    /// Every run of the sweep, in order.
    pub fn runs(&self) -> Vec<RunParams> {
        let base = RunParams {
            scene: self.scene.clone(),
            seed: self.seed,
            method: self.method.clone(),
            dt: self.dt,
            n: self.n,
            steps: self.steps,
            sets: self
                .sets
                .iter()
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect(),
        };
        let a = &self.axes;
        // Each axis maps one run to as many runs as it has values; no axis keeps the run as is.
        type Apply<'a> = Box<dyn Fn(&RunParams) -> Vec<RunParams> + 'a>;
        fn over<'a, T: Clone + 'a>(
            values: &'a [T],
            set: impl Fn(&mut RunParams, T) + 'a,
        ) -> Apply<'a> {
            Box::new(move |p: &RunParams| {
                if values.is_empty() {
                    return vec![p.clone()];
                }
                values
                    .iter()
                    .map(|v| {
                        let mut q = p.clone();
                        set(&mut q, v.clone());
                        q
                    })
                    .collect()
            })
        }
        let mut axes: Vec<Apply> = vec![
            over(&a.method, |p, v| p.method = Some(v)),
            over(&a.dt, |p, v| p.dt = Some(v)),
            over(&a.n, |p, v| p.n = Some(v)),
            over(&a.steps, |p, v| p.steps = Some(v)),
        ];
        for (name, values) in &a.sets {
            axes.push(over(values, move |p, v| {
                p.sets.push((name.clone(), v));
                p.sets.sort();
            }));
        }
        axes.push(over(&a.seed, |p, v| p.seed = Some(v)));
        let mut runs = vec![base];
        for axis in &axes {
            runs = runs.iter().flat_map(axis).collect();
        }
        runs
    }
}

#[cfg(test)]
mod tests {
    use crate::sweep::SweepFile;
    use std::path::Path;

    fn parse(text: &str) -> Result<SweepFile, String> {
        SweepFile::parse(Path::new("s.toml"), text).map_err(|e| e.to_string())
    }

    #[test]
    fn axes_expand_in_a_fixed_order_with_seed_fastest() {
        let f = parse(
            "scene = \"gas\"\nsteps = 10\n[axes]\nseed = { from = 1, to = 3 }\nmethod = [\"event\", \"discrete\"]\n",
        )
        .expect("parses");
        let runs = f.runs();
        assert_eq!(runs.len(), 6);
        let order: Vec<(String, u64)> = runs
            .iter()
            .map(|r| (r.method.clone().unwrap_or_default(), r.seed.unwrap_or(0)))
            .collect();
        assert_eq!(order[0], ("event".into(), 1));
        assert_eq!(order[2], ("event".into(), 3));
        assert_eq!(order[3], ("discrete".into(), 1));
        assert!(runs.iter().all(|r| r.steps == Some(10)));
    }

    #[test]
    fn bad_files_name_the_key_and_what_to_do() {
        let e = parse("scene = \"gas\"\n[axes]\nspeed = [1]\n").expect_err("unknown axis");
        assert!(e.contains("line 3") && e.contains("speed"), "{e}");
        let e = parse("scene = \"gas\"\n[axes]\nmethod = [\"fast\"]\n").expect_err("method");
        assert!(e.contains("method") && e.contains("fast"), "{e}");
        let e = parse("scene = \"gas\"\n[axes.set]\nSPEED = [1]\n").expect_err("built-in");
        assert!(e.contains("built-in"), "{e}");
        let e = parse("scene = \"a.rhai\"\n[axes]\ndt = []\n").expect_err("empty");
        assert!(e.contains("axes.dt"), "{e}");
        let e =
            parse("scene = \"a.rhai\"\n[axes]\nseed = { from = 3, to = 1 }\n").expect_err("range");
        assert!(e.contains("axes.seed"), "{e}");
    }

    #[test]
    fn constants_keep_their_type_as_text() {
        let f = parse("scene = \"a.rhai\"\n[set]\nA = 2.0\n[axes.set]\nB = [1, \"x\", true]\n")
            .expect("parses");
        let runs = f.runs();
        assert_eq!(runs.len(), 3);
        assert_eq!(
            runs[0].sets,
            vec![("A".into(), "2.0".into()), ("B".into(), "1".into())]
        );
        assert_eq!(runs[1].sets[1].1, "x");
        assert_eq!(runs[2].sets[1].1, "true");
    }
}
