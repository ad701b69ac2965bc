//! Runs every script test (`fn test_*()` in scripts/tests/*.rhai) as its own cargo test, so
//! `cargo test` and `cargo nextest run` cover the rules written in rhai by name.

use critterbox::testing::{discover, find_test_files, run_one, TestOptions};
use libtest_mimic::{Arguments, Failed, Trial};
use std::path::PathBuf;

fn main() {
    let args = Arguments::from_args();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    // Script tests name files relative to the crate root (load_scene("scripts/scenes/...")).
    std::env::set_current_dir(&root).expect("the crate root exists");
    let files =
        find_test_files(&[PathBuf::from("scripts/tests")]).expect("scripts/tests is readable");
    let trials = discover(&files, None)
        .into_iter()
        .map(|case| {
            let name = case.id().replace(".rhai::", "::").replace('/', "::");
            Trial::test(name, move || {
                let options = TestOptions {
                    jobs: 1,
                    ..TestOptions::default()
                };
                let outcome = run_one(&case, &options);
                match outcome.failure {
                    None => Ok(()),
                    // A failing test's own lines come with its failure, as `critterbox test`
                    // prints them.
                    Some(f) if outcome.output.is_empty() => Err(Failed::from(f.to_string())),
                    Some(f) => Err(Failed::from(format!(
                        "{f}\n---- output ----\n{}",
                        outcome.output.join("\n")
                    ))),
                }
            })
        })
        .collect();
    libtest_mimic::run(&args, trials).exit();
}
