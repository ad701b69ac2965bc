//! Comparing recorded and replayed states bit for bit, and saying where they first differ.

use super::schema::StateMsg;

fn show(x: f64) -> String {
    format!("{} ({:#018x})", ryu::Buffer::new().format(x), x.to_bits())
}

fn who(s: &StateMsg, i: usize) -> String {
    format!(
        "critter {} ({})",
        crate::recording::schema::id_of(s.id[i]),
        s.kind_name(i)
    )
}

/// The first difference between two full states, in slot order: which critter and which field,
/// with both values. `None` when they are bit-identical. `a_name` and `b_name` say which is
/// which (e.g. "recorded", "replayed").
pub fn first_difference(a: &StateMsg, b: &StateMsg, a_name: &str, b_name: &str) -> Option<String> {
    if a.step != b.step {
        return Some(format!("steps {} and {} compared", a.step, b.step));
    }
    let n = a.len().min(b.len());
    for i in 0..n {
        if a.id[i] != b.id[i] {
            return Some(format!(
                "the critter in slot order {i} is {} {a_name} but {} {b_name}",
                who(a, i),
                who(b, i)
            ));
        }
        if a.kind_name(i) != b.kind_name(i) {
            return Some(format!(
                "{}: kind {} {a_name}, {} {b_name}",
                who(a, i),
                a.kind_name(i),
                b.kind_name(i)
            ));
        }
        let (fa, fb) = (a.fields(i), b.fields(i));
        if fa.len() != fb.len() {
            return Some(format!("{}: 2D in one, 3D in the other", who(a, i)));
        }
        for ((name, x), (_, y)) in fa.iter().zip(&fb) {
            if x.to_bits() != y.to_bits() {
                return Some(format!(
                    "{}: {name} {a_name} {}, {b_name} {}",
                    who(a, i),
                    show(*x),
                    show(*y)
                ));
            }
        }
        if a.fixed[i] != b.fixed[i] || a.alive[i] != b.alive[i] {
            return Some(format!(
                "{}: fixed/alive {a_name} {}/{}, {b_name} {}/{}",
                who(a, i),
                a.fixed[i],
                a.alive[i],
                b.fixed[i],
                b.alive[i]
            ));
        }
        let key = a.id[i].to_string();
        let (pa, pb) = (a.props.get(&key), b.props.get(&key));
        let json =
            |p: Option<&crate::critter::Props>| serde_json::to_string(&p).unwrap_or_default();
        if json(pa) != json(pb) {
            return Some(format!(
                "{}: properties {a_name} {}, {b_name} {}",
                who(a, i),
                json(pa),
                json(pb)
            ));
        }
        let (ca, cb) = (a.colors.get(&key), b.colors.get(&key));
        if ca != cb {
            let show = |c: Option<&String>| c.map_or("its kind's".to_string(), |c| c.clone());
            return Some(format!(
                "{}: colour {a_name} {}, {b_name} {}",
                who(a, i),
                show(ca),
                show(cb)
            ));
        }
    }
    if a.len() != b.len() {
        let (longer, name) = if a.len() > b.len() {
            (a, a_name)
        } else {
            (b, b_name)
        };
        return Some(format!(
            "{} critters {a_name}, {} {b_name}; the first extra one ({name}) is {}",
            a.len(),
            b.len(),
            who(longer, n)
        ));
    }
    let json = |s: &StateMsg| serde_json::to_string(&s.walls).unwrap_or_default();
    if json(a) != json(b) {
        return Some("the wall boxes differ".to_string());
    }
    if !same_json(&a.vars, &b.vars) {
        let json = |s: &StateMsg| serde_json::to_string(&s.vars).unwrap_or_default();
        return Some(format!(
            "world().vars {a_name} {}, {b_name} {}",
            json(a),
            json(b)
        ));
    }
    None
}

/// True when two messages encode to the same JSON (floats in shortest round-trip form, so equal
/// text means equal bits).
pub fn same_json<T: serde::Serialize>(a: &T, b: &T) -> bool {
    match (serde_json::to_vec(a), serde_json::to_vec(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}
