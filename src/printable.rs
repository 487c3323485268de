//! Text from outside (radio names, relay names, error strings, paths) made safe to print on a
//! terminal: a control character in a droid's advertised name could move the cursor, clear
//! the screen or retitle the window of whoever lists it.

/// `s` with every control character shown as `·`.
pub fn clean(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_control() { '·' } else { c })
        .collect()
}

#[cfg(test)]
mod tests {
    #[test]
    fn control_characters_are_shown_not_obeyed() {
        assert_eq!(super::clean("D2-\u{1b}[2J\r\n\u{7}AB"), "D2-·[2J···AB");
        assert_eq!(super::clean("BB-8 ✓"), "BB-8 ✓");
    }
}
