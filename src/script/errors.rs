//! Turning rhai's errors into [`ScriptError`]s that name file, line, column and give a hint.
//!
//! rhai gives no position for some errors (a missing function called from Rust, a hook that
//! returns the wrong type): those get the hook's own definition line, found in the source.

use crate::error::ScriptError;
use rhai::{EvalAltResult, ParseError, ParseErrorType, Position};

fn locate(err: &mut ScriptError, pos: Position) {
    if let Some(line) = pos.line() {
        err.line = Some(line);
        err.column = pos.position();
    }
}

/// A syntax error in `text`, the file `file`'s. rhai finds an unclosed bracket only where it
/// runs out of text (the end of the file) or at the next `fn` (which it then finds inside a
/// block): those errors are placed at the bracket that is never closed ([`unclosed_bracket`]).
pub(crate) fn parse_error(file: &str, text: &str, e: &ParseError) -> ScriptError {
    let pos = e.position();
    let at_end = pos
        .line()
        .is_none_or(|l| rest_is_blank(text, l, pos.position().unwrap_or(1)));
    let inside_block = matches!(e.err_type(), ParseErrorType::WrongFnDefinition);
    if at_end || inside_block {
        if let Some((line, column, open)) = unclosed_bracket(text) {
            let (close, what) = match open {
                '(' => (')', "parenthesis"),
                '[' => (']', "bracket"),
                _ => ('}', "brace"),
            };
            let mut err =
                ScriptError::new(file, format!("syntax error: this '{open}' is never closed"));
            err.line = Some(line);
            err.column = Some(column);
            let found = match pos.line() {
                Some(l) if !at_end => format!(" (rhai noticed at line {l}: {})", e.err_type()),
                _ => format!(" (rhai reached the end of the file: {})", e.err_type()),
            };
            err.hint = Some(format!(
                "close the {what} with '{close}' where it ends{found}; `critterbox check FILE` \
                 checks scripts without running them"
            ));
            return err;
        }
    }
    let mut err = ScriptError::new(file, format!("syntax error: {}", e.err_type()));
    locate(&mut err, pos);
    err.hint = Some(
        "fix the syntax at that place; `critterbox check FILE` checks scripts without running them"
            .into(),
    );
    err
}

/// True when nothing but white space follows line `line`, column `column` (1-based) of `text`.
fn rest_is_blank(text: &str, line: usize, column: usize) -> bool {
    let mut lines = text.lines().skip(line.saturating_sub(1));
    let Some(first) = lines.next() else {
        return true;
    };
    let rest: String = first.chars().skip(column.saturating_sub(1)).collect();
    rest.trim().is_empty() && lines.all(|l| l.trim().is_empty())
}

/// An opening bracket of `text`, `(`, `[` or `{`, that is never closed: its 1-based line and
/// column, and the bracket. Comments, strings and characters are skipped. Where the brackets
/// pair up wrong, the first opener paired with a closer of another shape, or with a `}` that
/// begins a line left of the opener's line (indentation says the `}` closes an outer block),
/// is the one; else the last opener left unclosed at the end.
pub(crate) fn unclosed_bracket(text: &str) -> Option<(usize, usize, char)> {
    struct Open {
        ch: char,
        line: usize,
        column: usize,
        indent: usize,
    }
    let chars: Vec<char> = text.chars().collect();
    let mut stack: Vec<Open> = Vec::new();
    let mut suspect: Option<(usize, usize, char)> = None;
    let (mut i, mut line, mut column) = (0, 1, 1);
    let mut indent = 0;
    let mut line_blank = true;
    // Moves past `n` characters, keeping the line and column.
    let step = |i: &mut usize, line: &mut usize, column: &mut usize, n: usize| {
        for _ in 0..n {
            if *i < chars.len() {
                if chars[*i] == '\n' {
                    *line += 1;
                    *column = 1;
                } else {
                    *column += 1;
                }
                *i += 1;
            }
        }
    };
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if c == '\n' {
            step(&mut i, &mut line, &mut column, 1);
            indent = 0;
            line_blank = true;
            continue;
        }
        if line_blank && (c == ' ' || c == '\t') {
            indent += 1;
            step(&mut i, &mut line, &mut column, 1);
            continue;
        }
        let first_on_line = line_blank;
        line_blank = false;
        match (c, next) {
            ('/', Some('/')) => {
                while i < chars.len() && chars[i] != '\n' {
                    step(&mut i, &mut line, &mut column, 1);
                }
            }
            ('/', Some('*')) => {
                // rhai's block comments nest.
                let mut depth = 0;
                while i < chars.len() {
                    if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                        depth += 1;
                        step(&mut i, &mut line, &mut column, 2);
                    } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                        depth -= 1;
                        step(&mut i, &mut line, &mut column, 2);
                        if depth == 0 {
                            break;
                        }
                    } else {
                        step(&mut i, &mut line, &mut column, 1);
                    }
                }
            }
            ('"', _) | ('`', _) | ('\'', _) => {
                step(&mut i, &mut line, &mut column, 1);
                while i < chars.len() && chars[i] != c {
                    let n = if chars[i] == '\\' { 2 } else { 1 };
                    step(&mut i, &mut line, &mut column, n);
                }
                step(&mut i, &mut line, &mut column, 1);
            }
            ('(' | '[' | '{', _) => {
                stack.push(Open {
                    ch: c,
                    line,
                    column,
                    indent,
                });
                step(&mut i, &mut line, &mut column, 1);
            }
            (')' | ']' | '}', _) => {
                if let Some(open) = stack.pop() {
                    let pair = matches!((open.ch, c), ('(', ')') | ('[', ']') | ('{', '}'));
                    let outdented = c == '}' && first_on_line && indent < open.indent;
                    if (!pair || outdented) && suspect.is_none() {
                        suspect = Some((open.line, open.column, open.ch));
                    }
                }
                step(&mut i, &mut line, &mut column, 1);
            }
            _ => step(&mut i, &mut line, &mut column, 1),
        }
    }
    let last = stack.last().map(|o| (o.line, o.column, o.ch));
    match (suspect, last) {
        (Some(s), Some(_)) => Some(s),
        (_, last) => last.or(suspect),
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_unclosed_brace_of_a_function_is_found_at_its_line() {
        let text = "const A = 1;\nfn update(me, dt) {\n    me.vel = vec(1.0, 0.0);\n";
        assert_eq!(unclosed_bracket(text), Some((2, 19, '{')));
    }

    #[test]
    fn an_inner_block_left_open_is_found_by_the_indentation_of_the_closer() {
        let text = "fn update(me, dt) {\n    if me.pos.x > 1.0 {\n        me.vel = vec(0, 0);\n}\n\nfn init(me) {\n}\n";
        assert_eq!(unclosed_bracket(text), Some((2, 23, '{')));
    }

    #[test]
    fn brackets_in_comments_strings_and_characters_are_not_counted() {
        let text =
            "// {\n/* ( /* [ */ */\nlet s = \"{\\\"(\";\nlet t = `}`;\nlet c = '{';\nfn f() {\n";
        assert_eq!(unclosed_bracket(text), Some((6, 8, '{')));
        assert_eq!(unclosed_bracket("fn f() { g(\"}\"); }\n"), None);
    }

    #[test]
    fn a_syntax_error_at_the_end_of_the_file_is_placed_at_the_unclosed_brace() {
        let engine = rhai::Engine::new();
        let text = "fn update(me, dt) {\n    if true {\n        let x = 1;\n}\n";
        let e = engine.compile(text).expect_err("does not parse");
        let err = parse_error("kinds/k.rhai", text, &e);
        assert_eq!((err.line, err.column), (Some(2), Some(13)), "{err}");
        assert!(err.message.contains("never closed"), "{err}");
        // An error with a place of its own keeps it.
        let text = "fn update(me, dt) {\n    let = 1;\n}\n";
        let e = engine.compile(text).expect_err("does not parse");
        let err = parse_error("kinds/k.rhai", text, &e);
        assert_eq!(err.line, Some(2), "{err}");
    }
}
