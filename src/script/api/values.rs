//! Script values to engine values and back: numbers, `Vec`s, critter properties.

use super::{fail, CritterRef, Res};
use crate::critter::{PropValue, Props};
use crate::vector::Vector;
use glam::DVec3;
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
                d,
                d.type_name()
            ))
        },
        Ok,
    )
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
                d.type_name()
            ))
        },
        Ok,
    )
}

/// A script value as a critter property.
pub(crate) fn to_prop(d: &Dynamic) -> Res<PropValue> {
    if let Some(b) = d.clone().try_cast::<bool>() {
        return Ok(PropValue::Bool(b));
    }
    if let Some(i) = d.clone().try_cast::<INT>() {
        return Ok(PropValue::Int(i));
    }
    if let Some(x) = d.clone().try_cast::<f64>() {
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
