//! Hot reload: a kind file edited while its run goes on replaces the kind between two steps.
//!
//! The kind is rebuilt from the new text, and so is every loaded kind that extends it (from its
//! own text, so it inherits the new hooks). Then the world's kinds are replaced
//! ([`crate::World::replace_kind`]): critters keep their state, new ones get the new defaults.
//! A text that does not compile or declare changes nothing.

use super::host::Dim;
use super::kind_file::{build, load_into, ScriptKind, ScriptKindDef};
use super::Runtime;
use crate::error::{Error, ScriptError};
use crate::world::World;
use std::rc::Rc;

/// Replaces the kind that `file` defines with the one `text` defines, in the runtime and in
/// `world`; returns the names of the kinds replaced (that one first, then those that extend
/// it). `file` is the path as the kind was loaded (as in the run's sources).
pub(crate) fn reload<V: Dim>(
    rt: &Rc<Runtime>,
    world: &mut World<V>,
    file: &str,
    text: &str,
) -> Result<Vec<String>, Error> {
    let old: Vec<Rc<ScriptKindDef>> = rt.kinds.borrow().values().cloned().collect();
    let Some(target) = old.iter().find(|d| d.file == file).cloned() else {
        let mut e = ScriptError::new(file, "this file defines no kind loaded in this run");
        e.hint = Some("only the files of kinds the run loaded can be reloaded".into());
        return Err(Error::from(e));
    };
    // The kind, then each kind that extends it, parents before children.
    let mut order = vec![target.clone()];
    let mut rest: Vec<Rc<ScriptKindDef>> = old
        .iter()
        .filter(|d| d.name != target.name && extends(d, &target.name))
        .cloned()
        .collect();
    rest.sort_by_key(|d| depth(d));
    order.extend(rest);

    let rebuilt = rebuild_all(rt, &order, text);
    let defs = match rebuilt {
        Ok(defs) => defs,
        Err(e) => {
            // Nothing changes: the old kinds go back.
            let mut kinds = rt.kinds.borrow_mut();
            for d in &order {
                kinds.insert(d.name.clone(), d.clone());
            }
            return Err(e);
        }
    };
    for def in &defs {
        let Ok(id) = world.kinds().id(&def.name) else {
            continue;
        };
        let parent = match def.parent.as_deref() {
            Some(p) if p != "ball" && p != "wall" => {
                load_into(rt, world, p)?;
                Some(p)
            }
            other => other,
        };
        let hooks = Rc::new(ScriptKind::new(def.clone(), rt.clone()));
        world.replace_kind(id, parent, def.defaults.clone(), hooks)?;
    }
    Ok(defs.iter().map(|d| d.name.clone()).collect())
}

/// Builds `order[0]` from `text` and the others from their own texts, each put among the
/// runtime's kinds as it is built (so the next finds its new parent).
fn rebuild_all(
    rt: &Runtime,
    order: &[Rc<ScriptKindDef>],
    text: &str,
) -> Result<Vec<Rc<ScriptKindDef>>, Error> {
    let mut defs = Vec::with_capacity(order.len());
    for (i, d) in order.iter().enumerate() {
        let text = if i == 0 { text } else { &d.text };
        let def = build(rt, d.file.clone(), d.name.clone(), text)?;
        rt.kinds.borrow_mut().insert(d.name.clone(), def.clone());
        defs.push(def);
    }
    Ok(defs)
}

/// True when `d` extends the kind `name`, directly or not.
fn extends(d: &ScriptKindDef, name: &str) -> bool {
    let mut p = d.parent_def.clone();
    while let Some(def) = p {
        if def.name == name {
            return true;
        }
        p = def.parent_def.clone();
    }
    false
}

/// How many script kinds `d` extends.
fn depth(d: &ScriptKindDef) -> usize {
    std::iter::successors(d.parent_def.clone(), |p| p.parent_def.clone()).count()
}
