//! What the second round of hooks sees: `Contact` (`collide`'s third argument and
//! `touch_begin`'s), the `parent_*` calls that reach a parent kind's hook, and `me.age`.

use super::registry::Api;
use super::values::to_svec;
use super::{fail, num_or, Res};
use crate::critter::CritterId;
use crate::script::api::CritterRef;
use crate::script::env::Env;
use crate::script::host::with_env;
use crate::script::kind_file::{parent_collide, parent_collides_with, parent_plain};
use crate::step::access::HookContact;
use crate::vector::Vector;
use glam::DVec3;
use rhai::Dynamic;
use std::cell::Cell;
use std::rc::Rc;

/// A contact as scripts see it: fixed when the hook is called, except `impulse`, which reads
/// the call's last `collide_default` as it is now.
#[derive(Clone, Debug, Default)]
pub(crate) struct ScriptContact {
    normal: DVec3,
    point: DVec3,
    depth: f64,
    speed: f64,
    first: bool,
    impulse: Option<Rc<Cell<f64>>>,
}

impl<V: Vector> From<&HookContact<V>> for ScriptContact {
    fn from(c: &HookContact<V>) -> Self {
        ScriptContact {
            normal: to_svec(c.normal),
            point: to_svec(c.point),
            depth: c.depth,
            speed: c.speed,
            first: c.first,
            impulse: None,
        }
    }
}

impl ScriptContact {
    /// The same contact, its `impulse` read from `cell`.
    pub(crate) fn with_impulse(mut self, cell: Rc<Cell<f64>>) -> Self {
        self.impulse = Some(cell);
        self
    }

    /// The contact of `me` with `other` where they are now.
    pub(crate) fn between<V: Vector>(
        env: &Env<'_, V>,
        me: CritterId,
        other: CritterId,
        first: bool,
    ) -> Res<Self> {
        match (env.critter(me), env.critter(other)) {
            (Some(a), Some(b)) => Ok(ScriptContact::from(&HookContact::between(
                env.topology(),
                a,
                b,
                first,
            ))),
            _ => fail("the contact's critters are gone"),
        }
    }
}

pub(super) fn register(api: &mut Api) {
    api.engine
        .register_type_with_name::<ScriptContact>("Contact");
    api.engine
        .register_get("normal", |c: &mut ScriptContact| c.normal);
    api.engine
        .register_get("point", |c: &mut ScriptContact| c.point);
    api.engine
        .register_get("depth", |c: &mut ScriptContact| c.depth);
    api.engine
        .register_get("speed", |c: &mut ScriptContact| c.speed);
    api.engine
        .register_get("first", |c: &mut ScriptContact| c.first);
    api.engine.register_get("impulse", |c: &mut ScriptContact| {
        c.impulse.as_ref().map_or(0.0, |cell| cell.get())
    });
    let show = |c: &mut ScriptContact| {
        format!(
            "contact(normal {}, depth {}, speed {}, first {})",
            c.normal, c.depth, c.speed, c.first
        )
    };
    api.engine.register_fn("to_string", show);
    api.engine.register_fn("to_debug", show);

    api.func("parent_collide", |h| {
        move |me: &mut CritterRef, other: CritterRef| -> Res<bool> {
            parent_collide(&h, me.0, other.0, None)
        }
    });
    api.func("parent_collide", |h| {
        move |me: &mut CritterRef, other: CritterRef, contact: ScriptContact| -> Res<bool> {
            parent_collide(&h, me.0, other.0, Some(contact))
        }
    });
    api.func("parent_collides_with", |h| {
        move |me: &mut CritterRef, other: CritterRef| -> Res<rhai::INT> {
            parent_collides_with(&h, me.0, other.0)
        }
    });
    api.func("parent_update", |h| {
        move |me: &mut CritterRef, dt: Dynamic| -> Res<()> {
            let dt = num_or(&dt, "dt")?;
            parent_plain(&h, "update", me.0, Some(dt))
        }
    });
    api.func("parent_init", |h| {
        move |me: &mut CritterRef| -> Res<()> { parent_plain(&h, "init", me.0, None) }
    });

    api.get("age", |h| {
        move |me: &mut CritterRef| -> Res<f64> {
            let id = me.0;
            with_env!(h, env => match env.age(id) {
                Some(age) => Ok(age),
                None if env.critter(id).is_some() => fail("age cannot be read in collides_with"),
                None => Err(super::critter::gone(id)),
            })
        }
    });
}
