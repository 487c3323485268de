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

#[cfg(test)]
mod tests {
    use super::super::{Action, parse};
    use super::MatrixAction;
    use std::time::Duration;

    fn one(line: &str) -> Result<Action, String> {
        parse(line)
            .map(|mut s| s.remove(0).action)
            .map_err(|e| e[0].message.clone())
    }

    #[test]
    fn matrix_tank_and_calibrate_lines() {
        assert_eq!(
            one(r#"matrix text "HI THERE" 255 0 0"#),
            Ok(Action::Matrix(MatrixAction::Text {
                text: "HI THERE".into(),
                rgb: [255, 0, 0]
            }))
        );
        assert_eq!(
            one("matrix text HI"),
            Ok(Action::Matrix(MatrixAction::Text {
                text: "HI".into(),
                rgb: [255, 255, 255]
            }))
        );
        assert_eq!(
            one("matrix char A"),
            Ok(Action::Matrix(MatrixAction::Char {
                ch: 'A',
                rgb: [255, 255, 255]
            }))
        );
        assert_eq!(
            one("matrix fill 1 2 3"),
            Ok(Action::Matrix(MatrixAction::Fill([1, 2, 3])))
        );
        assert_eq!(
            one("matrix pixel 7 0 9 9 9"),
            Ok(Action::Matrix(MatrixAction::Pixel {
                x: 7,
                y: 0,
                rgb: [9, 9, 9]
            }))
        );
        assert_eq!(one("matrix clear"), Ok(Action::Matrix(MatrixAction::Clear)));
        assert_eq!(
            one("matrix rotate 180"),
            Ok(Action::Matrix(MatrixAction::Rotate(180)))
        );
        assert_eq!(
            one("tank 200 -100 for 1.5s"),
            Ok(Action::Tank {
                left: 200,
                right: -100,
                duration: Some(Duration::from_millis(1500))
            })
        );
        assert_eq!(one("calibrate compass"), Ok(Action::CalibrateCompass));
        for (bad, says) in [
            ("matrix pixel 8 0", "x"),
            ("matrix char AB", "one printable"),
            ("matrix text \"unclosed", "unclosed"),
            (&format!("matrix text {}", "x".repeat(26)), "1 to 25"),
            ("matrix rotate 45", "0, 90"),
            ("matrix", "expected"),
            ("tank 300 0", "left track"),
            ("tank 1 2 in 3s", "for"),
            ("calibrate gyro", "unknown calibration"),
        ] {
            let e = one(bad).unwrap_err();
            assert!(e.contains(says), "{bad}: {e}");
        }
    }
}
