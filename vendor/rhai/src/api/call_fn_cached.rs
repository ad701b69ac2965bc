//! Calling a script function with its function resolutions kept from one call to the next (a
//! critterbox patch, see `PATCH.md`).
//!
//! [`Engine::call_fn`] resolves every function a call makes afresh: its resolution cache lives
//! for one call and keeps an entry only when a call site is met a second time. An engine that
//! calls the same hook thousands of times per step keeps one [`FnCallCache`] per hook instead.
#![cfg(not(feature = "no_function"))]
#![cfg(not(feature = "no_ast"))]

use crate::eval::Caches;
use crate::func::ScriptFuncDef;
use crate::types::dynamic::Variant;
use crate::{
    CallFnOptions, Engine, FnArgsVec, FuncArgs, Position, RhaiResultOf, Scope, Shared,
    SharedModule, AST, ERR,
};
#[cfg(feature = "no_std")]
use std::prelude::v1::*;
use std::any::type_name;

/// Function resolutions kept across calls of [`Engine::call_fn_cached`] on one [`AST`].
///
/// Resolutions depend on the engine's functions and the AST's, so a cache is for one engine
/// only; it starts afresh by itself when given another AST.
#[derive(Debug, Clone, Default)]
pub struct FnCallCache {
    caches: Caches,
    /// The functions of the AST the resolutions were made with.
    lib: Option<SharedModule>,
    /// The script functions called so far, by name and number of parameters: finding one in
    /// the AST compares its name with every function's.
    fns: Vec<(String, usize, Shared<ScriptFuncDef>)>,
}

impl Engine {
    /// [`Engine::call_fn_with_options`], with the function resolutions of earlier calls on the
    /// same [`AST`] kept in `cache` and reused. `cache` must be used with this engine only.
    pub fn call_fn_cached<T: Variant + Clone>(
        &self,
        cache: &mut FnCallCache,
        options: CallFnOptions,
        scope: &mut Scope,
        ast: &AST,
        fn_name: impl AsRef<str>,
        args: impl FuncArgs,
    ) -> RhaiResultOf<T> {
        let lib = ast.shared_lib();
        if !cache.lib.as_ref().map_or(false, |l| Shared::ptr_eq(l, lib)) {
            cache.caches = Caches::new();
            cache.lib = Some(lib.clone());
            cache.fns.clear();
        }
        // The call's own level, made here so the call leaves it in place for the next one.
        if cache.caches.fn_resolution_caches_len() == 0 {
            cache.caches.push_fn_resolution_cache();
        }
        let mut arg_values = FnArgsVec::new_const();
        args.parse(&mut arg_values);

        let name = fn_name.as_ref();
        let found = cache.script_fn(ast, name, arg_values.len());
        let result = self._call_fn_found(
            options,
            scope,
            ast,
            name,
            arg_values.as_mut(),
            &mut self.new_global_runtime_state(),
            &mut cache.caches,
            found.as_deref(),
        );
        // Only the call's own level is kept: an inner one belongs to what pushed it.
        cache.caches.rewind_fn_resolution_caches(1);

        result.and_then(|result| {
            result.try_cast_result().map_err(|r| {
                let result_type = self.map_type_name(r.type_name());
                let cast_type = match type_name::<T>() {
                    typ if typ.contains("::") => self.map_type_name(typ),
                    typ => typ,
                };
                ERR::ErrorMismatchOutputType(cast_type.into(), result_type.into(), Position::NONE)
                    .into()
            })
        })
    }
}

impl FnCallCache {
    /// The script function `name` of `ast` with `num_params` parameters, found once.
    fn script_fn(
        &mut self,
        ast: &AST,
        name: &str,
        num_params: usize,
    ) -> Option<Shared<ScriptFuncDef>> {
        if let Some((.., f)) = self
            .fns
            .iter()
            .find(|(n, p, _)| *p == num_params && n == name)
        {
            return Some(f.clone());
        }
        let f = ast.shared_lib().get_script_fn(name, num_params)?.clone();
        self.fns.push((name.to_string(), num_params, f.clone()));
        Some(f)
    }
}
