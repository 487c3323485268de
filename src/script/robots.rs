//! Mission lines for the newer robots: BOLT's matrix (`matrix text "HI" 255 0 0`,
//! `matrix char A`, `matrix fill R G B`, `matrix pixel X Y R G B`, `matrix clear`,
//! `matrix rotate 90`), RVR's tracks (`tank LEFT RIGHT [for DURATION]`) and BOLT's compass
//! (`calibrate compass`).

use super::{Action, for_duration, int};

/// What a `matrix` line draws.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MatrixAction {
    /// Scroll text once (up to 25 ASCII characters).
    Text {
        text: String,
        rgb: [u8; 3],
    },
    /// Show one character.
    Char {
        ch: char,
        rgb: [u8; 3],
    },
    Fill([u8; 3]),
    Pixel {
        x: u8,
        y: u8,
        rgb: [u8; 3],
    },
    /// All pixels off.
    Clear,
    /// 0, 90, 180 or 270 degrees.
    Rotate(u16),
}

fn rgb(words: &[&str], usage: &str) -> Result<[u8; 3], String> {
    match words {
        [] => Ok([255, 255, 255]),
        [r, g, b] => Ok([
            int(r, "red", 0, 255)?,
            int(g, "green", 0, 255)?,
            int(b, "blue", 0, 255)?,
        ]),
        _ => Err(format!("expected `{usage}`")),
    }
}

/// `matrix …`; `content` is the whole line (text may be quoted with spaces inside).
pub fn parse_matrix(content: &str, words: &[&str]) -> Result<Action, String> {
    let what = words
        .get(1)
        .map(|w| w.to_ascii_lowercase())
        .unwrap_or_default();
    let a = match what.as_str() {
        "text" => {
            let usage = "matrix text \"TEXT\" [R G B]";
            let rest = content
                .splitn(3, char::is_whitespace)
                .nth(2)
                .unwrap_or("")
                .trim();
            let (text, after) = match rest.strip_prefix('"') {
                Some(q) => {
                    let end = q
                        .find('"')
                        .ok_or_else(|| format!("unclosed quote in `{usage}`"))?;
                    (q[..end].to_string(), &q[end + 1..])
                }
                None => {
                    let (t, a) = rest.split_once(char::is_whitespace).unwrap_or((rest, ""));
                    (t.to_string(), a)
                }
            };
            if text.is_empty() || text.len() > 25 || !text.is_ascii() {
                return Err("matrix text takes 1 to 25 ASCII characters".into());
            }
            let colour: Vec<&str> = after.split_whitespace().collect();
            MatrixAction::Text {
                text,
                rgb: rgb(&colour, usage)?,
            }
        }
        "char" => {
            let usage = "matrix char C [R G B]";
            let c = words.get(2).ok_or_else(|| format!("expected `{usage}`"))?;
            let mut chars = c.chars();
            let ch = match (chars.next(), chars.next()) {
                (Some(ch), None) if ch.is_ascii_graphic() => ch,
                _ => return Err(format!("{c:?} is not one printable ASCII character")),
            };
            MatrixAction::Char {
                ch,
                rgb: rgb(&words[3..], usage)?,
            }
        }
        "fill" => MatrixAction::Fill(rgb(&words[2..], "matrix fill R G B")?),
        "pixel" => {
            let usage = "matrix pixel X Y [R G B]";
            if words.len() < 4 {
                return Err(format!("expected `{usage}`"));
            }
            MatrixAction::Pixel {
                x: int(words[2], "x", 0, 7)?,
                y: int(words[3], "y", 0, 7)?,
                rgb: rgb(&words[4..], usage)?,
            }
        }
        "clear" if words.len() == 2 => MatrixAction::Clear,
        "rotate" if words.len() == 3 => {
            let deg: u16 = int(words[2], "rotation", 0, 270)?;
            if !deg.is_multiple_of(90) {
                return Err("matrix rotate takes 0, 90, 180 or 270".into());
            }
            MatrixAction::Rotate(deg)
        }
        _ => {
            return Err(
                "expected `matrix text \"TEXT\" [R G B]`, `matrix char C [R G B]`, `matrix fill R G B`, \
                 `matrix pixel X Y [R G B]`, `matrix clear` or `matrix rotate DEGREES`"
                    .into(),
            );
        }
    };
    Ok(Action::Matrix(a))
}

/// `tank LEFT RIGHT [for DURATION]`: each track −255..=255 (negative backs up).
pub fn parse_tank(words: &[&str]) -> Result<Action, String> {
    let usage = "tank LEFT RIGHT [for DURATION]";
    if words.len() != 3 && words.len() != 5 {
        return Err(format!("expected `{usage}`"));
    }
    let track = |w: &str, name: &str| -> Result<i16, String> {
        w.parse::<i16>()
            .ok()
            .filter(|v| (-255..=255).contains(v))
            .ok_or_else(|| format!("{name} track {w:?} is not in -255..=255"))
    };
    let duration = for_duration(words, usage)?;
    Ok(Action::Tank {
        left: track(words[1], "left")?,
        right: track(words[2], "right")?,
        duration,
    })
}
