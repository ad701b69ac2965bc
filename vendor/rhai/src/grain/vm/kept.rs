//! A [`Vm`]'s reusable parts kept between calls (a critterbox patch, see `PATCH.md`).
//!
//! [`Vm::new`] starts with empty function-resolution caches, a fresh runtime state and an empty
//! operand stack, and a call by name looks its function up and interns its parameter names. A
//! host that calls the same program's functions thousands of times keeps all of that in a
//! [`VmKeep`] instead and calls through [`Vm::call_fn_kept`].

use super::Vm;
use crate::eval::{Caches, GlobalRuntimeState};
use crate::grain::Program;
use crate::types::dynamic::Variant;
use crate::{
    CallFnOptions, Dynamic, Engine, EvalAltResult, FuncArgs, ImmutableString, Position,
    RhaiResultOf, Scope, Shared,
};
#[cfg(feature = "no_std")]
use std::prelude::v1::*;

/// What a [`Vm`] keeps from one call to the next: its runtime state, its resolution caches, its
/// operand stack and the functions called so far. For one engine only; it starts afresh by
/// itself when given another program.
#[derive(Debug, Default)]
pub struct VmKeep {
    global: Option<Box<GlobalRuntimeState>>,
    caches: Box<Caches>,
    stack: Vec<Dynamic>,
    /// The address and debug id of the program the entries below were made for.
    program: Option<(usize, u128)>,
    /// Functions called so far.
    fns: Vec<KeptFn>,
}

/// A function called through a [`VmKeep`]: its name, number of parameters, index among the
/// program's functions, and its parameters' interned names.
type KeptFn = (ImmutableString, usize, usize, Shared<[ImmutableString]>);

impl<'e> Vm<'e> {
    /// A [`Vm`] made of what `keep` holds (fresh parts when it holds none), its runtime state
    /// set back to what [`Vm::new`] starts with. Give the parts back with [`Vm::keep`].
    #[inline(always)]
    pub fn from_keep(engine: &'e Engine, keep: &mut VmKeep) -> Self {
        let caches = std::mem::take(&mut keep.caches);
        let stack = std::mem::take(&mut keep.stack);
        match keep.global.take() {
            Some(mut global) => {
                fresh(engine, &mut global);
                let mut vm = Self::from_parts(engine, global, caches, stack);
                vm.owns_trace = true;
                vm
            }
            None => {
                let mut vm = Self::new(engine);
                vm.caches = caches;
                vm.stack = stack;
                vm
            }
        }
    }

    /// Puts this [`Vm`]'s reusable parts back into `keep` for the next [`Vm::from_keep`].
    #[inline(always)]
    pub fn keep(mut self, keep: &mut VmKeep) {
        self.stack.clear();
        keep.stack = self.stack;
        keep.caches = self.caches;
        keep.global = Some(self.global);
    }

    /// [`Vm::call_fn_with_options`] with the function, its parameter names and the function
    /// resolutions of earlier calls taken from `keep`, and the arguments put straight on the
    /// operand stack. As [`Engine::call_fn_with_options`] does, an `exit` ends the call with its
    /// value, and an error inside the called function is returned as itself rather than
    /// wrapped in a call to that function.
    #[inline(always)]
    pub fn call_fn_kept<T: Variant + Clone>(
        engine: &'e Engine,
        keep: &mut VmKeep,
        options: CallFnOptions,
        scope: &mut Scope,
        program: &Program,
        name: &str,
        args: impl FuncArgs,
    ) -> RhaiResultOf<T> {
        // Resolutions and functions found are for one program: a keep given another one (another
        // address or other diagnostics) starts afresh.
        let id = (core::ptr::from_ref(program) as usize, program.debug_id());
        if keep.program != Some(id) {
            *keep = VmKeep::default();
            keep.program = Some(id);
        }
        let mut vm = Vm::from_keep(engine, keep);
        let result = if options.eval_ast || options.this_ptr.is_some() {
            vm.call_fn_with_options(options, scope, program, name, args)
        } else {
            vm.call_kept(&mut keep.fns, options, scope, program, name, args)
        };
        vm.keep(keep);
        result
    }

    fn call_kept<T: Variant + Clone>(
        &mut self,
        fns: &mut Vec<KeptFn>,
        options: CallFnOptions,
        scope: &mut Scope,
        program: &Program,
        name: &str,
        args: impl FuncArgs,
    ) -> RhaiResultOf<T> {
        if let Some(tag) = options.tag {
            self.global.tag = tag;
        }
        let orig_scope_len = scope.len();
        let result = self.with_environment(program, None, |vm| {
            let first = vm.stack.len();
            args.parse(&mut vm.stack);
            let argc = vm.stack.len() - first;
            let Some((index, names)) = kept_function(vm.engine, fns, program, name, argc) else {
                vm.stack.truncate(first);
                return Err(Box::new(EvalAltResult::ErrorFunctionNotFound(
                    format!("{name} ({argc} args)"),
                    Position::NONE,
                )));
            };
            let function = &program.functions()[index];
            vm.preset_names = Some(names);
            let (result, _) = vm.call_function_on_stack(
                program,
                name,
                &function.params,
                function.chunk,
                first,
                0,
                scope,
                options.rewind_scope,
                Position::NONE,
                None,
            );
            vm.preset_names = None;

            #[cfg(feature = "debugging")]
            let result = vm.at_end(scope).and(result);
            result
        });

        if options.rewind_scope {
            scope.rewind(orig_scope_len);
        }

        let value = result.or_else(|err| match *err {
            EvalAltResult::Exit(out, ..) => Ok(out),
            EvalAltResult::ErrorInFunctionCall(fn_name, _, inner, _) if fn_name == name => {
                Err(inner)
            }
            _ => Err(err),
        })?;
        self.cast_result(value)
    }
}

/// The index of `program`'s function `name` of `argc` parameters, and its parameters' interned
/// names: from `fns` when an earlier call found it, else looked up and added there.
fn kept_function(
    engine: &Engine,
    fns: &mut Vec<KeptFn>,
    program: &Program,
    name: &str,
    argc: usize,
) -> Option<(usize, Shared<[ImmutableString]>)> {
    if let Some((.., index, names)) = fns.iter().find(|(n, c, ..)| *c == argc && n == name) {
        return Some((*index, names.clone()));
    }
    let index = program.functions().iter().position(|f| {
        f.params.len() == argc && f.this_type.is_none() && program.name(f.name) == Some(name)
    })?;
    let names: Shared<[ImmutableString]> = program.functions()[index]
        .params
        .iter()
        .map(|&p| engine.get_interned_string(program.name(p).unwrap_or("")))
        .collect();
    fns.push((name.into(), argc, index, names.clone()));
    Some((index, names))
}

/// Sets a kept runtime state back to what `Engine::new_global_runtime_state` makes (a call
/// leaves most of it as it found it; the counts it leaves grown), keeping its allocations and
/// its fault trace.
fn fresh(engine: &Engine, global: &mut GlobalRuntimeState) {
    #[cfg(not(feature = "no_module"))]
    {
        global.truncate_imports(0);
        global.num_modules_loaded = 0;
        global.embedded_module_resolver = None;
        #[cfg(not(feature = "no_function"))]
        {
            global.constants = None;
        }
    }
    #[cfg(not(feature = "no_function"))]
    global.lib.clear();
    global.source = None;
    global.num_operations = Default::default();
    global.scope_level = 0;
    global.level = 0;
    global.always_search_scope = false;
    global.tag = engine.default_tag().clone();
}
