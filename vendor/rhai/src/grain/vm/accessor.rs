//! Property getters and setters of host types, called without making an error that an indexer
//! may make unnecessary (a critterbox patch, see `PATCH.md`).
//!
//! `x.p` calls `get$p`; when the type has no such getter, its string indexer `x["p"]` is tried,
//! and only when that fails too is the missing getter the error. Making that error first (a
//! formatted message) cost more than the indexer's call, on every property a script keeps in a
//! map behind an indexer.

use super::{malformed, Vm};
use crate::grain::Program;
use crate::{Dynamic, EvalAltResult, Position, RhaiResult, RhaiResultOf};
#[cfg(feature = "no_std")]
use std::prelude::v1::*;

impl Vm<'_> {
    /// `target.key` through the getter `getter` (`get$key`), else the string indexer.
    pub(super) fn get_property(
        &mut self,
        program: &Program,
        getter: u32,
        target: &mut Dynamic,
        key: &str,
        pos: Position,
    ) -> RhaiResult {
        let (engine, t0) = (self.engine, target.type_name());
        let (getter, hash) = accessor(program, getter, 1)?;
        match self.call_accessor(getter, hash, &mut [target], pos) {
            Ok(Some(value)) => Ok(value),
            Ok(None) => self.index_get(target, key, pos, || {
                engine.getter_not_found(getter, t0, pos)
            }),
            // A getter failing as a missing one does is followed by the indexer too, as in Rhai.
            Err(err) if matches!(*err, EvalAltResult::ErrorDotExpr(..)) => {
                self.index_get(target, key, pos, || err)
            }
            Err(err) => Err(err),
        }
    }

    /// `target.key = value` through the setter `setter` (`set$key`), else the string indexer;
    /// with `fail_silently`, a type with neither keeps its value without an error.
    pub(super) fn set_property(
        &mut self,
        program: &Program,
        setter: u32,
        target: &mut Dynamic,
        key: &str,
        value: &mut Dynamic,
        fail_silently: bool,
        pos: Position,
    ) -> RhaiResultOf<()> {
        let (engine, t0, t1) = (self.engine, target.type_name(), value.type_name());
        let (setter, hash) = accessor(program, setter, 2)?;
        match self.call_accessor(setter, hash, &mut [target, value], pos) {
            Ok(Some(_)) => Ok(()),
            Ok(None) => self.index_set(target, key, value, fail_silently, pos, || {
                engine.setter_not_found(setter, t0, t1, pos)
            }),
            Err(err) if matches!(*err, EvalAltResult::ErrorDotExpr(..)) => {
                self.index_set(target, key, value, fail_silently, pos, || err)
            }
            Err(err) => Err(err),
        }
    }

    /// `target["key"]`, or `missing()` when the type has no string indexer.
    fn index_get(
        &mut self,
        target: &mut Dynamic,
        key: &str,
        pos: Position,
        missing: impl FnOnce() -> Box<EvalAltResult>,
    ) -> RhaiResult {
        #[cfg(not(any(feature = "no_index", feature = "no_object")))]
        {
            let mut index = self.engine.get_interned_string(key).into();
            self.engine
                .call_indexer_get(&mut self.global, &mut self.caches, target, &mut index, pos)
                .map_err(|err| match *err {
                    EvalAltResult::ErrorIndexingType(..) => missing(),
                    _ => err.fill_position(pos),
                })
        }
        #[cfg(any(feature = "no_index", feature = "no_object"))]
        {
            let _ = (target, key, pos);
            Err(missing())
        }
    }

    /// `target["key"] = value`, or `missing()` when the type has no string indexer (nothing
    /// with `fail_silently`).
    fn index_set(
        &mut self,
        target: &mut Dynamic,
        key: &str,
        value: &mut Dynamic,
        fail_silently: bool,
        pos: Position,
        missing: impl FnOnce() -> Box<EvalAltResult>,
    ) -> RhaiResultOf<()> {
        #[cfg(not(any(feature = "no_index", feature = "no_object")))]
        {
            let mut index = self.engine.get_interned_string(key).into();
            match self.engine.call_indexer_set(
                &mut self.global,
                &mut self.caches,
                target,
                &mut index,
                value,
                true,
                pos,
            ) {
                Ok(_) => Ok(()),
                Err(err) if matches!(*err, EvalAltResult::ErrorIndexingType(..)) => {
                    if fail_silently {
                        Ok(())
                    } else {
                        Err(missing())
                    }
                }
                Err(err) => Err(err.fill_position(pos)),
            }
        }
        #[cfg(any(feature = "no_index", feature = "no_object"))]
        {
            let _ = (target, key, value, fail_silently, pos);
            Err(missing())
        }
    }

    /// A getter or setter called as the engine calls a native function by name, with `None`
    /// when there is none. Its name (`get$p`, `set$p`) is neither an operator nor a keyword, so
    /// what a call by name checks for those is skipped.
    fn call_accessor(
        &mut self,
        name: &str,
        hash: u64,
        args: &mut [&mut Dynamic],
        pos: Position,
    ) -> Result<Option<Dynamic>, Box<EvalAltResult>> {
        self.global.level += 1;
        let result = self.engine.exec_native_fn_call_or_none(
            &mut self.global,
            &mut self.caches,
            name,
            None,
            hash,
            args,
            true,
            false,
            false,
            pos,
        );
        self.global.level -= 1;
        result.map(|found| found.map(|(value, ..)| value))
    }
}

/// Accessor `index`'s name and its hash as a function of `argc` arguments.
fn accessor<'p>(program: &'p Program<'_>, index: u32, argc: usize) -> RhaiResultOf<(&'p str, u64)> {
    match (program.name(index), program.accessor_hash(index, argc)) {
        (Some(name), Some(hash)) => Ok((name, hash)),
        _ => Err(malformed(format!("no name {index}"))),
    }
}
