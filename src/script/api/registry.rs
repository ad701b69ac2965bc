//! How script functions are registered: [`Api`] gives each one its own handle on the host (the
//! way every function reaches the world, through `with_env!`), and keeps the list of the
//! functions whose string arguments name kinds, which `check` and the kind loader read
//! (`kind_refs`).
//!
//! Return types are bounded by `Any + Clone`: rhai's `Variant` is not exported, but its blanket
//! impl covers exactly those types.

use crate::script::host::Host;
use rhai::{Engine, RhaiNativeFunc};
use std::any::Any;
use std::collections::BTreeSet;
use std::rc::Rc;

/// Registers the script API on an engine (see the module docs).
pub(crate) struct Api<'a> {
    /// For what reaches no world: types, operators, constants.
    pub(crate) engine: &'a mut Engine,
    host: Rc<Host>,
    kind_calls: BTreeSet<&'static str>,
}

/// What custom syntax runs (rhai's `Engine::register_custom_syntax`).
pub(crate) type Syntax = Box<
    dyn Fn(
            &mut rhai::EvalContext,
            &[rhai::Expression],
        ) -> Result<rhai::Dynamic, Box<rhai::EvalAltResult>>
        + 'static,
>;

/// rhai's names for a property's getter and setter and for the indexer: `x.name` calls
/// `get$name`, `x[i]` calls `index$get$` (what `Engine::register_get` and the like register).
const GET: &str = "get$";
const SET: &str = "set$";
const INDEX_GET: &str = "index$get$";
const INDEX_SET: &str = "index$set$";

impl<'a> Api<'a> {
    pub(crate) fn new(engine: &'a mut Engine, host: &Rc<Host>) -> Self {
        Api {
            engine,
            host: host.clone(),
            kind_calls: BTreeSet::new(),
        }
    }

    /// The host, for a callback that is not a script function (`on_print`, custom syntax).
    pub(crate) fn host(&self) -> Rc<Host> {
        self.host.clone()
    }

    /// Script function `name`: `make` is handed the host and returns what rhai calls.
    pub(crate) fn func<A, const N: usize, const X: bool, R, const F: bool, Fun>(
        &mut self,
        name: &'static str,
        make: impl FnOnce(Rc<Host>) -> Fun,
    ) -> &mut Self
    where
        A: 'static,
        R: Any + Clone,
        Fun: RhaiNativeFunc<A, N, X, R, F> + 'static,
    {
        self.engine.register_fn(name, make(self.host.clone()));
        self
    }

    /// [`Api::func`] for a function whose string arguments name kinds (`spawn("shard", ...)`,
    /// `me.nearby(2.0, "boid")`): a kind file that names one so is loaded with it, and `check`
    /// reports a name that is no kind.
    pub(crate) fn kind_func<A, const N: usize, const X: bool, R, const F: bool, Fun>(
        &mut self,
        name: &'static str,
        make: impl FnOnce(Rc<Host>) -> Fun,
    ) -> &mut Self
    where
        A: 'static,
        R: Any + Clone,
        Fun: RhaiNativeFunc<A, N, X, R, F> + 'static,
    {
        self.kind_calls.insert(name);
        self.func(name, make)
    }

    /// The getter of property `name` (`x.name`).
    pub(crate) fn get<A, const N: usize, const X: bool, R, const F: bool, Fun>(
        &mut self,
        name: &str,
        make: impl FnOnce(Rc<Host>) -> Fun,
    ) -> &mut Self
    where
        A: 'static,
        R: Any + Clone,
        Fun: RhaiNativeFunc<A, N, X, R, F> + 'static,
    {
        self.engine
            .register_fn(format!("{GET}{name}"), make(self.host.clone()));
        self
    }

    /// The setter of property `name` (`x.name = value`).
    pub(crate) fn set<A, const N: usize, const X: bool, const F: bool, Fun>(
        &mut self,
        name: &str,
        make: impl FnOnce(Rc<Host>) -> Fun,
    ) -> &mut Self
    where
        A: 'static,
        Fun: RhaiNativeFunc<A, N, X, (), F> + 'static,
    {
        self.engine
            .register_fn(format!("{SET}{name}"), make(self.host.clone()));
        self
    }

    /// The indexer's getter (`x[i]`).
    pub(crate) fn index_get<A, const N: usize, const X: bool, R, const F: bool, Fun>(
        &mut self,
        make: impl FnOnce(Rc<Host>) -> Fun,
    ) -> &mut Self
    where
        A: 'static,
        R: Any + Clone,
        Fun: RhaiNativeFunc<A, N, X, R, F> + 'static,
    {
        self.engine.register_fn(INDEX_GET, make(self.host.clone()));
        self
    }

    /// The indexer's setter (`x[i] = value`).
    pub(crate) fn index_set<A, const N: usize, const X: bool, const F: bool, Fun>(
        &mut self,
        make: impl FnOnce(Rc<Host>) -> Fun,
    ) -> &mut Self
    where
        A: 'static,
        Fun: RhaiNativeFunc<A, N, X, (), F> + 'static,
    {
        self.engine.register_fn(INDEX_SET, make(self.host.clone()));
        self
    }

    /// Custom syntax that calls like a function whose string arguments name kinds, its first
    /// symbol that function's name (`spawn(...)`: `spawn` is a reserved word in rhai).
    pub(crate) fn kind_syntax(
        &mut self,
        symbols: &[&'static str],
        make: impl FnOnce(Rc<Host>) -> Syntax,
    ) -> Result<(), rhai::ParseError> {
        if let Some(name) = symbols.first() {
            self.kind_calls.insert(name);
        }
        self.engine
            .register_custom_syntax(symbols, false, make(self.host.clone()))
            .map(drop)
    }

    /// The functions registered with [`Api::kind_func`] and [`Api::kind_syntax`].
    pub(crate) fn kind_calls(&self) -> Vec<&'static str> {
        self.kind_calls.iter().copied().collect()
    }
}
