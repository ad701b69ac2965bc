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
    CallFnOptions, Dynamic, Engine, FnArgsVec, FuncArgs, Position, RhaiResult, RhaiResultOf,
    Scope, Shared, SharedModule, AST, ERR,
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
        let lean = !options.eval_ast && options.this_ptr.is_none();
        #[cfg(feature = "debugging")]
        let lean = lean && !self.is_debugger_registered();
        let fn_def = if lean {
            cache.script_fn(ast, name, arg_values.len())
        } else {
            None
        };
        let result = match fn_def {
            Some(fn_def) => self.call_script_fn_lean(
                options,
                scope,
                ast,
                name,
                &fn_def,
                arg_values.as_mut(),
                &mut cache.caches,
            ),
            None => self._call_fn(
                options,
                scope,
                ast,
                name,
                arg_values.as_mut(),
                &mut self.new_global_runtime_state(),
                &mut cache.caches,
            ),
        };
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

    /// What [`Engine::_call_fn`] does for a script function `fn_def` of `ast` with no statements
    /// to evaluate first, no `this` and no debugger, without restoring a runtime state that is
    /// dropped right after.
    #[allow(clippy::too_many_arguments)]
    fn call_script_fn_lean(
        &self,
        options: CallFnOptions,
        scope: &mut Scope,
        ast: &AST,
        name: &str,
        fn_def: &ScriptFuncDef,
        arg_values: &mut [Dynamic],
        caches: &mut Caches,
    ) -> RhaiResult {
        let global = &mut self.new_global_runtime_state();
        global.source = ast.source_raw().cloned();
        global.lib.push(ast.shared_lib().clone());
        if let Some(tag) = options.tag {
            global.tag = tag;
        }
        #[cfg(not(feature = "no_module"))]
        {
            global.embedded_module_resolver = ast.resolver.clone();
        }
        let args = &mut arg_values.iter_mut().collect::<FnArgsVec<_>>();
        let result = (|| {
            #[cfg(not(feature = "no_closure"))]
            #[cfg(not(feature = "unchecked"))]
            crate::func::ensure_no_data_race(name, args, false)?;
            self.call_script_fn(
                global.into(),
                caches,
                scope,
                None,
                None,
                fn_def,
                args,
                options.rewind_scope,
                Position::NONE,
            )
            .or_else(|err| match *err {
                ERR::Exit(out, ..) => Ok(out),
                _ => Err(err),
            })
        })();
        result.map_err(|err| match *err {
            ERR::ErrorInFunctionCall(fn_name, _, inner_err, _) if fn_name == name => inner_err,
            _ => err,
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
