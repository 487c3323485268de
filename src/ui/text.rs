//! Text helpers for fixed-width cells: display width, truncation with an ellipsis, and
//! number formatting that never produces a 40-character float or panics on NaN.
//!
//! Widths go through ratatui's own measure ([`Span::width`]) so what we truncate is what the
//! buffer will lay out.

use ratatui::style::Style;
use ratatui::text::Span;
use std::fmt::Write;

/// Display width of a string, in terminal cells.
pub fn width(s: &str) -> usize {
    Span::raw(s).width()
}

fn char_width(c: char) -> usize {
    let mut b = [0u8; 4];
    width(c.encode_utf8(&mut b))
}

/// Replace control characters (from droid names, error strings, paths) so they cannot move
/// the cursor or break a row.
pub use crate::printable::clean;

/// Keep the start of `s` within `max` cells, ending with `…` when cut.
pub fn truncate(s: &str, max: usize) -> String {
    if width(s) <= max {
        return s.to_string();
    }
    if max == 0 {
        return String::new();
    }
    let mut out = String::new();
    let mut used = 0;
    for c in s.chars() {
        let w = char_width(c);
        if used + w > max - 1 {
            break;
        }
        out.push(c);
        used += w;
    }
    out.push('…');
    out
}

/// Keep the start of `s` within `max` cells, cut between words (ending with `…`): a message
/// too long for its row loses its last words, never half of one.
pub fn truncate_words(s: &str, max: usize) -> String {
    if width(s) <= max {
        return s.to_string();
    }
    let cut = truncate(s, max);
    let body = cut.trim_end_matches('…');
    // The next character of `s` after the cut: a space means the cut fell between words.
    let next = s[body.len()..].chars().next();
    if next.is_some_and(char::is_whitespace) {
        return format!("{}…", body.trim_end());
    }
    match body.rfind(char::is_whitespace) {
        Some(i) if i > 0 => format!("{}…", body[..i].trim_end()),
        _ => cut,
    }
}

/// Keep the end of `s` within `max` cells, starting with `…` when cut (paths: the file name
/// matters more than the home directory).
pub fn truncate_left(s: &str, max: usize) -> String {
    if width(s) <= max {
        return s.to_string();
    }
    if max == 0 {
        return String::new();
    }
    let mut tail = Vec::new();
    let mut used = 0;
    for c in s.chars().rev() {
        let w = char_width(c);
        if used + w > max - 1 {
            break;
        }
        tail.push(c);
        used += w;
    }
    let mut out = String::from("…");
    out.extend(tail.into_iter().rev());
    out
}

/// Exactly `w` cells: truncated, then padded on the right.
pub fn fit(s: &str, w: usize) -> String {
    let mut t = truncate(s, w);
    let pad = w.saturating_sub(width(&t));
    t.extend(std::iter::repeat_n(' ', pad));
    t
}

/// Exactly `w` cells, right-aligned (numbers).
pub fn fit_right(s: &str, w: usize) -> String {
    let t = truncate(s, w);
    let pad = w.saturating_sub(width(&t));
    let mut out: String = std::iter::repeat_n(' ', pad).collect();
    out.push_str(&t);
    out
}

/// A float with `prec` decimals, bounded in width: huge values switch to exponent form and
/// NaN/inf print as such instead of as garbage.
pub fn num(v: f32, prec: usize) -> String {
    if v.is_nan() {
        return "NaN".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { "inf".into() } else { "-inf".into() };
    }
    let mut s = String::new();
    if v.abs() >= 1e5 {
        let _ = write!(s, "{v:.1e}");
    } else {
        // No "-0.0" (and no flicker around zero).
        s = crate::units::fixed(f64::from(v), prec);
    }
    s
}

/// A rate, per second, in the one form every panel uses (issue 39 point 13: `10/s` in the
/// status bar, `10.0/s` in the sensors' title for the same stream): one decimal below 10,
/// whole numbers from there, as shown (9.96 is `10/s`, never `10.0/s`).
pub fn per_second(v: f32) -> String {
    let prec = if (v.abs() * 10.0).round() < 100.0 {
        1
    } else {
        0
    };
    format!("{}/s", num(v, prec))
}

/// An optional reading: `-` until it has been received.
pub fn opt(v: Option<f32>, prec: usize, unit: &str) -> String {
    match v {
        Some(v) => format!("{}{unit}", num(v, prec)),
        None => "-".into(),
    }
}

/// A value as a fraction of `range` for gauges: 0 for NaN, clamped to -1..=1.
pub fn unit_fraction(v: f32, range: f32) -> f32 {
    if !v.is_finite() || !range.is_finite() || range <= 0.0 {
        return 0.0;
    }
    (v / range).clamp(-1.0, 1.0)
}

/// A list of items joined by `sep` (key hints: "o aim · c main colour") wrapped into lines
/// of at most `w` cells between items, never inside one: a hint cut mid-word reads as a
/// different key. An item wider than a line is cut with `…`.
pub fn wrap_items(s: &str, sep: &str, w: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut cur = String::new();
    for item in s.split(sep).map(str::trim).filter(|i| !i.is_empty()) {
        if !cur.is_empty() && width(&cur) + width(sep) + width(item) <= w {
            cur.push_str(sep);
            cur.push_str(item);
            continue;
        }
        if !cur.is_empty() {
            lines.push(std::mem::take(&mut cur));
        }
        cur = truncate(item, w);
    }
    if !cur.is_empty() {
        lines.push(cur);
    }
    lines
}

/// Greedy word wrap into lines of at most `w` cells; words longer than a line are split.
pub fn wrap(s: &str, w: usize) -> Vec<String> {
    let w = w.max(1);
    let mut lines = Vec::new();
    let mut cur = String::new();
    let mut cur_w = 0;
    for word in s.split_whitespace() {
        let ww = width(word);
        if cur_w > 0 && cur_w + 1 + ww <= w {
            cur.push(' ');
            cur.push_str(word);
            cur_w += 1 + ww;
            continue;
        }
        if cur_w > 0 {
            lines.push(std::mem::take(&mut cur));
            cur_w = 0;
        }
        for c in word.chars() {
            let cw = char_width(c);
            if cur_w + cw > w && cur_w > 0 {
                lines.push(std::mem::take(&mut cur));
                cur_w = 0;
            }
            cur.push(c);
            cur_w += cw;
        }
    }
    if cur_w > 0 || lines.is_empty() {
        lines.push(cur);
    }
    lines
}

/// Merge per-cell (symbol, style) pairs into one span per run of equal style, so a 100-cell
/// bar costs a handful of spans rather than a hundred.
pub fn runs(cells: impl IntoIterator<Item = (char, Style)>) -> Vec<Span<'static>> {
    let mut spans = Vec::new();
    let mut cur: Option<(String, Style)> = None;
    for (c, style) in cells {
        match &mut cur {
            Some((s, st)) if *st == style => s.push(c),
            _ => {
                if let Some((s, st)) = cur.take() {
                    spans.push(Span::styled(s, st));
                }
                cur = Some((c.to_string(), style));
            }
        }
    }
    if let Some((s, st)) = cur {
        spans.push(Span::styled(s, st));
    }
    spans
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 39 point 13: a rate near 10 does not switch between "10" and "10.0"; every
    /// panel's rates are in this one form.
    #[test]
    fn rates_have_one_form() {
        assert_eq!(per_second(10.0), "10/s");
        assert_eq!(per_second(9.94), "9.9/s");
        assert_eq!(per_second(9.96), "10/s");
        assert_eq!(per_second(9.8), "9.8/s");
        assert_eq!(per_second(0.0), "0.0/s");
        assert_eq!(per_second(100.0), "100/s");
        assert_eq!(per_second(f32::NAN), "NaN/s");
    }

    #[test]
    fn key_hints_wrap_between_items_never_inside_one() {
        let h = "o aim (heading 0) · c main colour · b back light";
        assert_eq!(wrap_items(h, " · ", 80), [h]);
        assert_eq!(
            wrap_items(h, " · ", 36),
            ["o aim (heading 0) · c main colour", "b back light"]
        );
        assert_eq!(
            wrap_items(h, " · ", 10),
            ["o aim (he…", "c main co…", "b back li…"]
        );
        assert!(wrap_items("", " · ", 10).is_empty());
    }

    #[test]
    fn words_are_cut_whole() {
        assert_eq!(
            truncate_words("capped at 10/s — stream less", 18),
            "capped at 10/s —…"
        );
        assert_eq!(truncate_words("capped at 10/s", 20), "capped at 10/s");
        assert_eq!(truncate_words("one two three", 8), "one two…");
        assert_eq!(truncate_words("abcdefghij", 5), "abcd…");
    }

    #[test]
    fn truncation_keeps_width() {
        assert_eq!(truncate("hello world", 6), "hello…");
        assert_eq!(truncate("hi", 6), "hi");
        assert_eq!(truncate("hello", 0), "");
        assert_eq!(truncate_left("/home/me/droid.log", 10), "…droid.log");
        assert_eq!(fit("ab", 4), "ab  ");
        assert_eq!(fit_right("ab", 4), "  ab");
        assert_eq!(fit("abcdef", 4), "abc…");
        assert_eq!(
            wrap("turn left (hold; also aims)", 10),
            ["turn left", "(hold;", "also aims)"]
        );
        assert_eq!(wrap("abcdefghij", 4), ["abcd", "efgh", "ij"]);
        assert_eq!(wrap("", 4), [""]);
    }

    #[test]
    fn numbers_stay_short() {
        assert_eq!(num(f32::NAN, 1), "NaN");
        assert_eq!(num(f32::NEG_INFINITY, 1), "-inf");
        assert_eq!(num(f32::MAX, 1), "3.4e38");
        assert_eq!(num(-0.01, 1), "0.0");
        assert_eq!(opt(None, 1, "°"), "-");
        assert_eq!(unit_fraction(f32::NAN, 1.0), 0.0);
        assert_eq!(unit_fraction(5.0, 2.0), 1.0);
    }
}
