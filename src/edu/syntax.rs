//! Syntax errors said where they are. Boa places errors found at the end of the file (a
//! missing `}`, a string never closed) nowhere (`abrupt end`), and says `expected token ';'`
//! for an `await` in a function that is not `async`; a program's author needs the line of
//! the `{` left open, of the string's opening quote, and the word `async`.

/// A place in the source, 1-based.
type At = (u32, u32);

/// The syntax error Boa gave (`message`, at `at` when it placed it), as the author needs it:
/// its place and what to do.
pub(super) fn explained(source: &str, message: &str, at: Option<At>) -> (At, String) {
    if let Some((line, col)) = at {
        let text = source
            .lines()
            .nth(line.saturating_sub(1) as usize)
            .unwrap_or("");
        if message.contains("expected token") && has_word(text, "await") {
            return (
                (line, col),
                "SyntaxError: `await` is only allowed inside an `async` function: write \
                 `async function …` (or `async () => …`) for the function around it"
                    .to_string(),
            );
        }
        return ((line, col), message.to_string());
    }
    match unclosed(source) {
        Some((at, what)) => (at, what),
        None => {
            let lines = source.lines().count().max(1) as u32;
            let last = source.lines().last().map_or(0, |l| l.chars().count()) as u32;
            (
                (lines, last + 1),
                format!("{message}: the program ends in the middle of something"),
            )
        }
    }
}

fn has_word(text: &str, word: &str) -> bool {
    text.match_indices(word).any(|(i, _)| {
        let ident = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
        !ident(text[..i].chars().last()) && !ident(text[i + word.len()..].chars().next())
    })
}

fn indent(line: &str) -> usize {
    line.chars().take_while(|c| *c == ' ' || *c == '\t').count()
}

/// What the file leaves open at its end: a string, template or comment (where it starts), or
/// a bracket; of the brackets, the first whose closing one is not indented as its line is
/// (the `}` that closes it belongs to another), else the innermost left open.
fn unclosed(source: &str) -> Option<(At, String)> {
    enum State {
        Code,
        Str(char, At),
        Template(At),
        Line,
        Block(At),
    }
    let lines: Vec<&str> = source.lines().collect();
    let mut state = State::Code;
    let mut open: Vec<(char, At)> = Vec::new();
    let mut suspect: Option<(char, At)> = None;
    for (li, text) in lines.iter().enumerate() {
        let line = li as u32 + 1;
        let chars: Vec<char> = text.chars().collect();
        let mut i = 0;
        while i < chars.len() {
            let c = chars[i];
            let at = (line, i as u32 + 1);
            let next = chars.get(i + 1).copied();
            match state {
                State::Code => match c {
                    '/' if next == Some('/') => state = State::Line,
                    '/' if next == Some('*') => {
                        state = State::Block(at);
                        i += 1;
                    }
                    '"' | '\'' => state = State::Str(c, at),
                    '`' => state = State::Template(at),
                    '{' | '(' | '[' => open.push((c, at)),
                    '}' | ')' | ']' => {
                        if let Some((o, from)) = open.pop() {
                            let first = chars[..i].iter().all(|ch| ch.is_whitespace());
                            let opened = lines.get(from.0 as usize - 1).copied().unwrap_or("");
                            if o == '{' && first && indent(opened) != indent(text) {
                                suspect.get_or_insert((o, from));
                            }
                        }
                    }
                    _ => {}
                },
                State::Str(q, _) => match c {
                    '\\' => i += 1,
                    _ if c == q => state = State::Code,
                    _ => {}
                },
                State::Template(_) => match c {
                    '\\' => i += 1,
                    '`' => state = State::Code,
                    _ => {}
                },
                State::Line => {}
                State::Block(_) => {
                    if c == '*' && next == Some('/') {
                        state = State::Code;
                        i += 1;
                    }
                }
            }
            if let State::Str(_, from) = state
                && i + 1 >= chars.len()
                && chars.last().is_none_or(|l| *l != '\\')
            {
                return Some((
                    from,
                    "SyntaxError: this string is never closed: its closing quote is missing \
                     on this line"
                        .to_string(),
                ));
            }
            i += 1;
        }
        if let State::Line = state {
            state = State::Code;
        }
        if let State::Str(_, from) = state {
            // An empty line after an opening quote at the end of the previous one.
            return Some((
                from,
                "SyntaxError: this string is never closed: its closing quote is missing".into(),
            ));
        }
    }
    match state {
        State::Template(from) => {
            return Some((
                from,
                "SyntaxError: this template (`…`) is never closed: its closing backquote is \
                 missing"
                    .into(),
            ));
        }
        State::Block(from) => {
            return Some((
                from,
                "SyntaxError: this comment is never closed: its `*/` is missing".into(),
            ));
        }
        _ => {}
    }
    let (o, at) = suspect.or_else(|| open.last().copied())?;
    let close = match o {
        '{' => '}',
        '(' => ')',
        _ => ']',
    };
    Some((
        at,
        format!("SyntaxError: this `{o}` is never closed: a `{close}` is missing"),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_brace_is_placed_at_the_brace_left_open() {
        let src = "async function startProgram() {\n  for (let i = 0; i < 3; i++) {\n    await roll(0, 50, 1);\n\n  setMainLed({ r: 1, g: 2, b: 3 });\n}\n";
        let ((line, col), m) = explained(src, "abrupt end", None);
        assert_eq!((line, col), (2, 31), "{m}");
        assert!(m.contains("a `}` is missing"), "{m}");
    }

    #[test]
    fn an_unterminated_string_is_placed_at_its_quote() {
        let src = "async function startProgram() {\n  speak(\"hello, false);\n}\n";
        let ((line, col), m) = explained(src, "abrupt end", None);
        assert_eq!((line, col), (2, 9), "{m}");
        assert!(m.contains("never closed"), "{m}");
    }

    #[test]
    fn await_outside_async_says_so() {
        let src = "function go() {\n  await delay(1);\n}\n";
        let (_, m) = explained(src, "expected token ';', got 'delay'", Some((2, 9)));
        assert!(m.contains("`async`"), "{m}");
    }
}
