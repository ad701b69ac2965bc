//! What a kind file's top level declares: `extends "parent";` and `defaults(#{ ... });`, kept in
//! the host while the file's top level runs.

use super::registry::Api;
use super::{fail, Res};
use crate::script::kind_file::KindDecl;
use rhai::{Dynamic, Map};

pub(super) fn register(api: &mut Api) {
    // extends "parent";
    let h = api.host();
    let registered =
        api.engine
            .register_custom_syntax(["extends", "$string$"], false, move |_ctx, inputs| {
                let parent = inputs[0].get_string_value().unwrap_or_default().to_string();
                match h.kind_decl.borrow_mut().as_mut() {
                    Some(decl) => {
                        decl.parent = Some(parent);
                        Ok(Dynamic::UNIT)
                    }
                    None => fail("`extends` belongs at the top of a kind file"),
                }
            });
    debug_assert!(registered.is_ok());
    api.func("defaults", |h| {
        move |ctx: rhai::NativeCallContext, map: Map| -> Res<()> {
            match h.kind_decl.borrow_mut().as_mut() {
                Some(KindDecl { defaults, .. }) => {
                    *defaults = Some((map, ctx.call_position()));
                    Ok(())
                }
                None => fail("defaults(#{ ... }) belongs in a kind file"),
            }
        }
    });
}
