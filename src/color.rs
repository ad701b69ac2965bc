//! Colours by name or `#rrggbb`: a kind's `color` default and a critter's `me.color`, as the
//! recording's Foxglove channel and the viewer draw them. Core, so a bad colour is refused where
//! it is set, not when it is drawn.

/// RGBA in [0, 1].
pub type Rgba = [f32; 4];

/// The colour names critterbox knows, with their RGB.
const NAMED: [(&str, [f32; 3]); 15] = [
    ("red", [0.9, 0.15, 0.15]),
    ("green", [0.2, 0.7, 0.25]),
    ("blue", [0.2, 0.4, 0.95]),
    ("orange", [1.0, 0.6, 0.1]),
    ("yellow", [0.95, 0.85, 0.15]),
    ("purple", [0.6, 0.3, 0.8]),
    ("cyan", [0.2, 0.8, 0.85]),
    ("magenta", [0.9, 0.35, 0.7]),
    ("pink", [0.9, 0.35, 0.7]),
    ("brown", [0.55, 0.35, 0.2]),
    ("black", [0.1, 0.1, 0.1]),
    ("white", [0.95, 0.95, 0.95]),
    ("gray", [0.65, 0.65, 0.7]),
    ("grey", [0.65, 0.65, 0.7]),
    ("silver", [0.65, 0.65, 0.7]),
];

/// The colour `c` names (a name above or `#rrggbb`, any case), if any.
pub fn parse(c: &str) -> Option<Rgba> {
    let c = c.trim().to_ascii_lowercase();
    if let Some(hex) = c.strip_prefix('#') {
        if hex.len() != 6 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
            return None;
        }
        let v = u32::from_str_radix(hex, 16).ok()?;
        let ch = |s: u32| ((v >> s) & 0xff) as f32 / 255.0;
        return Some([ch(16), ch(8), ch(0), 1.0]);
    }
    NAMED
        .iter()
        .find(|(name, _)| *name == c)
        .map(|(_, rgb)| [rgb[0], rgb[1], rgb[2], 1.0])
}

/// `c` trimmed and lower-cased if it is a colour, else why not (for error messages).
pub fn checked(c: &str) -> Result<String, String> {
    match parse(c) {
        Some(_) => Ok(c.trim().to_ascii_lowercase()),
        None => Err(format!(
            "not a colour: use #rrggbb (e.g. #ff8800) or one of {}",
            NAMED.map(|(n, _)| n).join(", ")
        )),
    }
}

/// Colour of a kind: its `color` default if it names a colour, else one from a palette by kind
/// index; walls are grey.
pub fn kind_color(name: &str, color: Option<&str>, index: usize) -> Rgba {
    if let Some(c) = color.and_then(parse) {
        return c;
    }
    if name == "wall" {
        return [0.55, 0.55, 0.6, 1.0];
    }
    const PALETTE: [Rgba; 6] = [
        [0.25, 0.55, 0.95, 1.0],
        [0.95, 0.55, 0.2, 1.0],
        [0.3, 0.75, 0.35, 1.0],
        [0.85, 0.3, 0.35, 1.0],
        [0.6, 0.4, 0.85, 1.0],
        [0.9, 0.8, 0.25, 1.0],
    ];
    PALETTE[index % PALETTE.len()]
}

/// `c` as `#rrggbb` (alpha dropped).
pub fn hex(c: Rgba) -> String {
    let ch = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    format!("#{:02x}{:02x}{:02x}", ch(c[0]), ch(c[1]), ch(c[2]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_and_names_parse_and_junk_does_not() {
        assert_eq!(parse("#ff0000"), Some([1.0, 0.0, 0.0, 1.0]));
        assert_eq!(parse(" #00FF00 "), Some([0.0, 1.0, 0.0, 1.0]));
        assert!(parse("Red").is_some());
        for bad in ["", "#ff00", "#gg0000", "#+f0000", "blurple", "#ff00000"] {
            assert!(parse(bad).is_none(), "{bad}");
            assert!(checked(bad).is_err(), "{bad}");
        }
        assert_eq!(checked(" RED ").as_deref(), Ok("red"));
    }

    #[test]
    fn hex_of_a_parsed_colour_gives_it_back() {
        for c in ["#000000", "#ffffff", "#12ab9f", "#ff8800"] {
            assert_eq!(parse(c).map(hex).as_deref(), Some(c));
        }
    }
}
