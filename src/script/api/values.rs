//! Script values to engine values and back: numbers, `Vec`s, critter properties.

use super::{fail, CritterRef, Res};
use crate::critter::{PropValue, Props};
use crate::vector::fmt_vec;
use crate::vector::Vector;
use glam::{DVec2, DVec3};
use rhai::{Array, Dynamic, ImmutableString, Map, INT};

/// A number from a script value (INT or FLOAT).
pub(crate) fn num(d: &Dynamic) -> Option<f64> {
    if let Some(x) = d.clone().try_cast::<f64>() {
        Some(x)
    } else {
        d.clone().try_cast::<INT>().map(|i| i as f64)
    }
}

/// A number from a script value, or an error naming `what` was expected.
pub(crate) fn num_or(d: &Dynamic, what: &str) -> Res<f64> {
    num(d).map_or_else(
        || {
            fail(format!(
                "{what} must be a number, got {} ({})",
                show(d),
                type_of(d)
            ))
        },
        Ok,
    )
}

/// A script `Vec` as users write one, in a world of `dim` dimensions: `(5, NaN)` in 2D, where
/// the script side's z (always 0) is left out, `(5, NaN, 1)` in 3D.
pub(crate) fn show_vec(v: DVec3, dim: usize) -> String {
    if dim == 2 {
        fmt_vec(DVec2::new(v.x, v.y))
    } else {
        fmt_vec(v)
    }
}

/// The dimension a `Vec` belongs to when no world says: 2 when its z is 0.
pub(crate) fn guess_dim(v: DVec3) -> usize {
    if v.z == 0.0 {
        2
    } else {
        3
    }
}

/// A script value for an error message, as users write it: vectors as `(x, y)`, inside arrays
/// and maps too (rhai's own text of a `Vec` is its Rust type's name).
pub(crate) fn show(d: &Dynamic) -> String {
    if let Some(v) = d.clone().try_cast::<DVec3>() {
        return show_vec(v, guess_dim(v));
    }
    if let Some(c) = d.clone().try_cast::<CritterRef>() {
        return format!("critter {}", c.0);
    }
    if let Some(a) = d.read_lock::<Array>() {
        let items: Vec<String> = a.iter().map(show).collect();
        return format!("[{}]", items.join(", "));
    }
    if let Some(m) = d.read_lock::<Map>() {
        let items: Vec<String> = m
            .iter()
            .map(|(k, v)| format!("{:?}: {}", k.as_str(), show(v)))
            .collect();
        return format!("#{{{}}}", items.join(", "));
    }
    if d.is_string() {
        return format!("{d:?}");
    }
    d.to_string()
}

/// The script name of a value's type (`Vec`, `Critter`), where rhai would give the Rust one.
pub(crate) fn type_of(d: &Dynamic) -> &'static str {
    if d.is::<DVec3>() {
        "Vec"
    } else if d.is::<CritterRef>() {
        "Critter"
    } else {
        d.type_name()
    }
}

/// An engine vector as a script `Vec` (z is 0 in 2D).
pub(crate) fn to_svec<V: Vector>(v: V) -> DVec3 {
    let a = v.to_array3();
    DVec3::new(a[0], a[1], a[2])
}

/// A script `Vec` as an engine vector (z is dropped in 2D).
pub(crate) fn from_svec<V: Vector>(s: DVec3) -> V {
    let mut v = V::zero();
    for axis in 0..V::DIM {
        v.set(axis, s[axis]);
    }
    v
}

/// A `Vec` from a script value, or an error naming `what` was expected.
pub(crate) fn vec_of(d: &Dynamic, what: &str) -> Res<DVec3> {
    d.clone().try_cast::<DVec3>().map_or_else(
        || {
            fail(format!(
                "{what} must be a Vec (e.g. vec(1.0, 2.0)), got {}",
                type_of(d)
            ))
        },
        Ok,
    )
}

/// A script value as a critter property.
pub(crate) fn to_prop(d: &Dynamic) -> Res<PropValue> {
    // Scalars, what update hooks set every step, are read without a clone.
    if let Ok(b) = d.as_bool() {
        return Ok(PropValue::Bool(b));
    }
    if let Ok(i) = d.as_int() {
        return Ok(PropValue::Int(i));
    }
    if let Ok(x) = d.as_float() {
        return Ok(PropValue::Float(x));
    }
    if let Some(s) = d.clone().try_cast::<ImmutableString>() {
        return Ok(PropValue::Text(s.to_string()));
    }
    if let Some(c) = d.clone().try_cast::<CritterRef>() {
        return Ok(PropValue::Critter(c.0));
    }
    if let Some(v) = d.clone().try_cast::<DVec3>() {
        return Ok(PropValue::Vector(v.to_array()));
    }
    if let Some(a) = d.clone().try_cast::<Array>() {
        return a
            .iter()
            .map(to_prop)
            .collect::<Res<Vec<_>>>()
            .map(PropValue::List);
    }
    if let Some(m) = d.clone().try_cast::<Map>() {
        return m
            .iter()
            .map(|(k, v)| Ok((k.to_string(), to_prop(v)?)))
            .collect::<Res<_>>()
            .map(PropValue::Map);
    }
    fail(format!(
        "a property or var can be a bool, number, string, Vec, critter, or an array or map of those, not {}",
        d.type_name()
    ))
}

/// A critter property as a script value.
pub(crate) fn from_prop(p: &PropValue) -> Dynamic {
    match p {
        PropValue::Bool(b) => Dynamic::from(*b),
        PropValue::Int(i) => Dynamic::from(*i),
        PropValue::Float(x) => Dynamic::from(*x),
        PropValue::Text(s) => Dynamic::from(s.clone()),
        PropValue::Critter(id) => Dynamic::from(CritterRef(*id)),
        PropValue::List(items) => Dynamic::from(items.iter().map(from_prop).collect::<Array>()),
        PropValue::Vector(v) => Dynamic::from(DVec3::from_array(*v)),
        PropValue::Map(m) => Dynamic::from(
            m.iter()
                .map(|(k, v)| (k.as_str().into(), from_prop(v)))
                .collect::<Map>(),
        ),
    }
}

/// Props given as a script map.
pub(crate) fn props_from_map(map: &Map) -> Res<Props> {
    let mut props = Props::new();
    for (name, v) in map {
        props.insert(name.to_string(), to_prop(v)?);
    }
    Ok(props)
}
