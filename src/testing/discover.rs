//! Finding test scripts and the tests in them.

use super::TestCase;
use crate::error::{Error, ScriptError};
use crate::script::{Runtime, ScriptOptions};
use std::path::PathBuf;

/// Test script files under `paths` (files as given; folders searched for `*.rhai`), sorted. A
/// path that is not there is an error: it was meant to hold tests.
pub fn find_test_files(paths: &[PathBuf]) -> Result<Vec<PathBuf>, Error> {
    let mut files = Vec::new();
    for p in paths {
        if !p.exists() {
            let mut e = ScriptError::new(
                p.display().to_string(),
                "no such file or folder: it was given as a test script or a folder of them",
            );
            e.hint = Some("test scripts are .rhai files with fn test_*() functions; paths are relative to the working directory".into());
            return Err(Error::from(e));
        }
        if p.is_dir() {
            let entries = std::fs::read_dir(p).map_err(|e| {
                Error::from(ScriptError::new(
                    p.display().to_string(),
                    format!("cannot list the folder: {e}"),
                ))
            })?;
            let mut found: Vec<PathBuf> = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "rhai"))
                .collect();
            found.sort();
            files.extend(found);
        } else {
            files.push(p.clone());
        }
    }
    Ok(files)
}

/// The tests in `files`: every `fn test_*()` without parameters. A file that does not compile
/// becomes one test that fails with its syntax error.
pub fn discover(files: &[PathBuf], filter: Option<&str>) -> Vec<TestCase> {
    let mut cases = Vec::new();
    // Compiling needs the engine's custom syntax (`spawn(...)`, `extends`), not the test API.
    let rt = Runtime::new(&ScriptOptions::default(), None);
    for file in files {
        let names: Vec<String> = match std::fs::read_to_string(file)
            .ok()
            .and_then(|t| rt.engine.compile(t).ok())
        {
            Some(ast) => {
                let mut names: Vec<String> = ast
                    .iter_functions()
                    .filter(|f| f.name.starts_with("test_") && f.params.is_empty())
                    .map(|f| f.name.to_string())
                    .collect();
                names.sort();
                names
            }
            None => vec![String::new()],
        };
        for name in names {
            let case = TestCase {
                file: file.clone(),
                name,
            };
            if filter.is_none_or(|f| case.id().contains(f)) {
                cases.push(case);
            }
        }
    }
    cases
}
