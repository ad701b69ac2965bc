//! The `/foxglove/scene` channel: critters as spheres and walls as cubes in Foxglove's
//! `foxglove.SceneUpdate` message, JSON-encoded, so a recording opens in Foxglove with the
//! critters drawn. Written on the steps that carry a full state.

use super::schema::{StateMsg, WallMsg};
use serde_json::{json, Value};
use std::fmt::Write;

pub use crate::color::{kind_color, Rgba};

fn num(out: &mut String, x: f64) {
    // Drawing needs no more than f32 (the state channel has the exact values); a non-finite
    // coordinate is drawn at 0.
    let x = if x.is_finite() { x as f32 } else { 0.0 };
    let mut buf = ryu::Buffer::new();
    out.push_str(buf.format_finite(x));
}

fn vec3(out: &mut String, v: [f64; 3]) {
    out.push_str("{\"x\":");
    num(out, v[0]);
    out.push_str(",\"y\":");
    num(out, v[1]);
    out.push_str(",\"z\":");
    num(out, v[2]);
    out.push('}');
}

fn color(c: Rgba) -> String {
    format!(
        "{{\"r\":{},\"g\":{},\"b\":{},\"a\":{}}}",
        c[0], c[1], c[2], c[3]
    )
}

/// Quaternion `[x, y, z, w]` of a wall's frame (2D: a turn about z).
fn orientation(w: &WallMsg) -> [f64; 4] {
    let axis = |i: usize, j: usize| w.axes.get(i).and_then(|a| a.0.get(j)).copied();
    if w.axes.len() == 2 {
        let (c, s) = (axis(0, 0).unwrap_or(1.0), axis(0, 1).unwrap_or(0.0));
        let half = s.atan2(c) / 2.0;
        return [0.0, 0.0, half.sin(), half.cos()];
    }
    // 3D: the rotation matrix whose columns are the axes.
    let m = |r: usize, c: usize| axis(c, r).unwrap_or(if r == c { 1.0 } else { 0.0 });
    let trace = m(0, 0) + m(1, 1) + m(2, 2);
    if trace > 0.0 {
        let s = (trace + 1.0).sqrt() * 2.0;
        [
            (m(2, 1) - m(1, 2)) / s,
            (m(0, 2) - m(2, 0)) / s,
            (m(1, 0) - m(0, 1)) / s,
            0.25 * s,
        ]
    } else if m(0, 0) > m(1, 1) && m(0, 0) > m(2, 2) {
        let s = (1.0 + m(0, 0) - m(1, 1) - m(2, 2)).sqrt() * 2.0;
        [
            0.25 * s,
            (m(0, 1) + m(1, 0)) / s,
            (m(0, 2) + m(2, 0)) / s,
            (m(2, 1) - m(1, 2)) / s,
        ]
    } else if m(1, 1) > m(2, 2) {
        let s = (1.0 + m(1, 1) - m(0, 0) - m(2, 2)).sqrt() * 2.0;
        [
            (m(0, 1) + m(1, 0)) / s,
            0.25 * s,
            (m(1, 2) + m(2, 1)) / s,
            (m(0, 2) - m(2, 0)) / s,
        ]
    } else {
        let s = (1.0 + m(2, 2) - m(0, 0) - m(1, 1)).sqrt() * 2.0;
        [
            (m(0, 2) + m(2, 0)) / s,
            (m(1, 2) + m(2, 1)) / s,
            0.25 * s,
            (m(1, 0) - m(0, 1)) / s,
        ]
    }
}

/// The `foxglove.SceneUpdate` JSON for a state: one entity, `critters`, replaced each time.
/// `colors` holds one colour per kind of `state.kinds`.
pub fn scene_update(state: &StateMsg, log_time_ns: u64, colors: &[Rgba]) -> String {
    let n = state.len();
    let mut out = String::with_capacity(256 + 170 * n);
    let _ = write!(
        out,
        "{{\"deletions\":[],\"entities\":[{{\"timestamp\":{{\"sec\":{},\"nsec\":{}}},\
         \"frame_id\":\"world\",\"id\":\"critters\",\"lifetime\":{{\"sec\":0,\"nsec\":0}},\
         \"frame_locked\":false,\"metadata\":[{{\"key\":\"step\",\"value\":\"{}\"}}],\
         \"arrows\":[],\"cubes\":[",
        log_time_ns / 1_000_000_000,
        log_time_ns % 1_000_000_000,
        state.step
    );
    let wall_color = color(kind_color("wall", None, 0));
    let kind_colors: Vec<String> = (0..state.kinds.len())
        .map(|k| color(colors.get(k).copied().unwrap_or([0.5, 0.5, 0.5, 1.0])))
        .collect();
    let thin = 2.0
        * state
            .radius
            .0
            .iter()
            .copied()
            .fold(0.05f64, f64::min)
            .max(0.05);
    for (k, w) in state.walls.iter().enumerate() {
        if k > 0 {
            out.push(',');
        }
        let c = |v: &[f64], i: usize| v.get(i).copied().unwrap_or(0.0);
        out.push_str("{\"pose\":{\"position\":");
        vec3(
            &mut out,
            [c(&w.center.0, 0), c(&w.center.0, 1), c(&w.center.0, 2)],
        );
        let q = orientation(w);
        let _ = write!(
            out,
            ",\"orientation\":{{\"x\":{},\"y\":{},\"z\":{},\"w\":{}}}}},\"size\":",
            q[0], q[1], q[2], q[3]
        );
        let size_z = if w.half.0.len() == 3 {
            2.0 * w.half.0[2]
        } else {
            thin
        };
        vec3(
            &mut out,
            [2.0 * c(&w.half.0, 0), 2.0 * c(&w.half.0, 1), size_z],
        );
        out.push_str(",\"color\":");
        out.push_str(&wall_color);
        out.push('}');
    }
    out.push_str("],\"spheres\":[");
    let mut first = true;
    let wall_kind = state.kinds.iter().position(|k| k == "wall");
    for i in 0..n {
        if Some(state.kind[i] as usize) == wall_kind {
            continue;
        }
        if !first {
            out.push(',');
        }
        first = false;
        out.push_str("{\"pose\":{\"position\":");
        vec3(&mut out, state.pos(i));
        out.push_str(",\"orientation\":{\"x\":0,\"y\":0,\"z\":0,\"w\":1}},\"size\":");
        let d = 2.0 * state.radius.0[i];
        vec3(&mut out, [d, d, d]);
        out.push_str(",\"color\":");
        // A colour a script gave the critter wins over its kind's.
        let own = (!state.colors.is_empty())
            .then(|| state.colors.get(&state.id[i].to_string()))
            .flatten()
            .and_then(|c| crate::color::parse(c));
        match own {
            Some(c) => out.push_str(&color(c)),
            None => out.push_str(
                kind_colors
                    .get(state.kind[i] as usize)
                    .map_or("{}", String::as_str),
            ),
        }
        out.push('}');
    }
    out.push_str("],\"cylinders\":[],\"lines\":[],\"triangles\":[],\"texts\":[],\"models\":[]}]}");
    out
}

/// A JSON Schema for `foxglove.SceneUpdate`, with the fields critterbox writes (the layout of
/// Foxglove's published schema for that message).
pub fn scene_update_schema() -> Value {
    let number = json!({ "type": "number" });
    let vector3 = json!({ "title": "foxglove.Vector3", "type": "object",
        "properties": { "x": number, "y": number, "z": number } });
    let quaternion = json!({ "title": "foxglove.Quaternion", "type": "object",
        "properties": { "x": number, "y": number, "z": number, "w": number } });
    let pose = json!({ "title": "foxglove.Pose", "type": "object",
        "properties": { "position": vector3, "orientation": quaternion } });
    let color = json!({ "title": "foxglove.Color", "type": "object",
        "properties": { "r": number, "g": number, "b": number, "a": number } });
    let time = json!({ "type": "object", "title": "time", "properties": {
        "sec": { "type": "integer", "minimum": 0 },
        "nsec": { "type": "integer", "minimum": 0, "maximum": 999_999_999 } } });
    let duration = json!({ "type": "object", "title": "duration", "properties": {
        "sec": { "type": "integer" },
        "nsec": { "type": "integer", "minimum": 0, "maximum": 999_999_999 } } });
    let shape = |title: &str| {
        json!({ "title": title, "type": "object",
            "properties": { "pose": pose, "size": vector3, "color": color } })
    };
    let any_array = json!({ "type": "array", "items": { "type": "object" } });
    json!({
        "title": "foxglove.SceneUpdate",
        "description": "An update to the entities displayed in a 3D scene",
        "type": "object",
        "properties": {
            "deletions": { "type": "array", "items": {
                "title": "foxglove.SceneEntityDeletion", "type": "object",
                "properties": { "timestamp": time, "type": { "type": "integer" },
                                "id": { "type": "string" } } } },
            "entities": { "type": "array", "items": {
                "title": "foxglove.SceneEntity", "type": "object",
                "properties": {
                    "timestamp": time,
                    "frame_id": { "type": "string" },
                    "id": { "type": "string" },
                    "lifetime": duration,
                    "frame_locked": { "type": "boolean" },
                    "metadata": { "type": "array", "items": {
                        "title": "foxglove.KeyValuePair", "type": "object",
                        "properties": { "key": { "type": "string" }, "value": { "type": "string" } } } },
                    "arrows": any_array,
                    "cubes": { "type": "array", "items": shape("foxglove.CubePrimitive") },
                    "spheres": { "type": "array", "items": shape("foxglove.SpherePrimitive") },
                    "cylinders": any_array,
                    "lines": any_array,
                    "triangles": any_array,
                    "texts": any_array,
                    "models": any_array,
                } } },
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::schema::Floats;

    #[test]
    fn scene_update_is_json_with_one_sphere_per_critter_and_a_cube_per_wall() {
        let state = StateMsg {
            step: 3,
            kinds: vec!["wall".into(), "ball".into()],
            id: vec![0, 1, 2],
            kind: vec![0, 1, 1],
            x: Floats(vec![0.0, 1.0, 2.0]),
            y: Floats(vec![0.0, 1.5, 2.5]),
            radius: Floats(vec![5.0, 0.5, 0.25]),
            walls: vec![WallMsg {
                id: 0,
                center: Floats(vec![0.0, 0.0]),
                half: Floats(vec![5.0, 0.1]),
                axes: vec![Floats(vec![0.0, 1.0]), Floats(vec![-1.0, 0.0])],
            }],
            ..StateMsg::default()
        };
        let text = scene_update(&state, 1_500_000_000, &[[0.0; 4], [1.0; 4]]);
        let v: Value = serde_json::from_str(&text).expect("valid JSON");
        let e = &v["entities"][0];
        assert_eq!(e["timestamp"]["sec"], 1);
        assert_eq!(e["timestamp"]["nsec"], 500_000_000);
        assert_eq!(e["spheres"].as_array().map(Vec::len), Some(2));
        assert_eq!(e["spheres"][1]["size"]["x"], 0.5);
        assert_eq!(e["cubes"].as_array().map(Vec::len), Some(1));
        // A wall turned a quarter turn: quaternion about z by 45 degrees' half-angle.
        let qz = e["cubes"][0]["pose"]["orientation"]["z"]
            .as_f64()
            .unwrap_or(0.0);
        assert!((qz - (std::f64::consts::FRAC_PI_4).sin()).abs() < 1e-12);
    }
}
