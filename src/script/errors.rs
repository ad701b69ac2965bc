//! Turning rhai's errors into [`ScriptError`]s that name file, line, column and give a hint.
//!
//! rhai gives no position for some errors (a missing function called from Rust, a hook that
//! returns the wrong type): those get the hook's own definition line, found in the source.

use crate::error::ScriptError;
use rhai::{EvalAltResult, ParseError, Position};

fn locate(err: &mut ScriptError, pos: Position) {
    if let Some(line) = pos.line() {
        err.line = Some(line);
        err.column = pos.position();
    }
}

/// A syntax error.
pub(crate) fn parse_error(file: &str, e: &ParseError) -> ScriptError {
    let mut err = ScriptError::new(file, format!("syntax error: {}", e.err_type()));
    locate(&mut err, e.position());
    err.hint = Some(
        "fix the syntax at that place; `critterbox check FILE` checks scripts without running them"
            .into(),
    );
    err
}

/// The text of an error without rhai's own " (line L, position P)" suffix.
fn bare(e: &EvalAltResult) -> String {
    match e {
        EvalAltResult::ErrorRuntime(value, _) => match value.clone().try_cast::<String>() {
            Some(s) => s,
            None => value.to_string(),
        },
        other => {
            let text = other.to_string();
            match text.rfind(" (line ") {
                Some(i) => text[..i].to_string(),
                None => text,
            }
        }
    }
}

/// A runtime error from running `hook` (defined at `hook_line` in `file`, if known).
pub(crate) fn eval_error(
    file: &str,
    hook: Option<&str>,
    hook_line: Option<(usize, usize)>,
    e: &EvalAltResult,
    max_operations: u64,
) -> ScriptError {
    let inner = e.unwrap_inner();
    let text = bare(inner);
    let (message, carried_hint) = match text.split_once(super::api::HINT_MARK) {
        Some((m, h)) => (m.to_string(), Some(h.to_string())),
        None => (text, None),
    };
    let mut err = ScriptError::new(file, message);
    err.hook = hook.map(str::to_string);
    // The innermost position is where it went wrong; fall back to outer ones, then to the hook.
    let mut pos = inner.position();
    if pos.is_none() {
        pos = e.position();
    }
    locate(&mut err, pos);
    if err.line.is_none() {
        if let Some((line, col)) = hook_line {
            err.line = Some(line);
            err.column = Some(col);
        }
    }
    // The file the innermost error happened in, when rhai knows it (a parent kind's hook).
    if let EvalAltResult::ErrorInFunctionCall(_, source, _, _) = e {
        if !source.is_empty() {
            err.file = source.to_string();
        }
    }
    err.hint = match inner {
        EvalAltResult::ErrorTooManyOperations(_) => {
            err.message = format!("the script ran more than {max_operations} operations in one call");
            Some("is there an endless loop? If the work is real, raise the limit with --max-ops".into())
        }
        EvalAltResult::ErrorFunctionNotFound(sig, _) => Some(format!(
            "no function matches {sig}: check the name and the types of the arguments; the script API is listed in docs/scripting.md"
        )),
        EvalAltResult::ErrorVariableNotFound(name, _) => Some(format!(
            "'{name}' is not defined here; functions cannot see variables of the top level, only constants (const) and their parameters"
        )),
        EvalAltResult::ErrorPropertyNotFound(name, _) => Some(format!(
            "no property '{name}'; critters have pos, vel, radius, mass, health, restitution, priority, fixed, alive, id, kind and user properties"
        )),
        EvalAltResult::ErrorStackOverflow(_) => Some("a function calls itself without end, or calls nest too deep".into()),
        EvalAltResult::ErrorDataTooLarge(what, _) => {
            let (data, flag) = too_large(what);
            err.message = format!("{data} grew past the sandbox's limit (--{flag})");
            Some(format!(
                "does a loop add to it without end? If the data is real, raise the limit with --{flag}"
            ))
        }
        EvalAltResult::ErrorTerminated(token, _) => {
            // The step's operations budget (api::step_ops) stops a script with its text.
            let text = token.to_string();
            match text.split_once(super::api::HINT_MARK) {
                Some((m, h)) => {
                    err.message = m.to_string();
                    Some(h.to_string())
                }
                None => carried_hint,
            }
        }
        _ => carried_hint,
    };
    err
}

/// What grew too large, in words, and the flag that limits it, from rhai's name of the data.
fn too_large(what: &str) -> (&'static str, &'static str) {
    if what.contains("string") {
        ("a string", "max-string")
    } else if what.contains("map") {
        ("a map (with the maps inside it)", "max-map")
    } else {
        ("an array (with the arrays inside it)", "max-array")
    }
}

/// Finds `fn name(` at the start of a line: the 1-based line and column of the definition.
pub(crate) fn fn_location(source: &str, name: &str) -> Option<(usize, usize)> {
    for (i, line) in source.lines().enumerate() {
        let trimmed = line.trim_start();
        let rest = trimmed
            .strip_prefix("private ")
            .unwrap_or(trimmed)
            .trim_start();
        if let Some(after) = rest.strip_prefix("fn ") {
            let after = after.trim_start();
            if let Some(tail) = after.strip_prefix(name) {
                if tail.trim_start().starts_with('(') {
                    return Some((i + 1, line.len() - trimmed.len() + 1));
                }
            }
        }
    }
    None
}
