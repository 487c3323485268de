//! The animation and sound palettes, loaded from the catalogues shipped in `assets/`.

/// One palette entry.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Entry {
    pub id: u16,
    pub name: String,
}

const ANIMATIONS: &str = include_str!("../../assets/animations.tsv");
const SOUNDS: &str = include_str!("../../assets/sounds.tsv");

/// Parse `id<TAB>name` lines; `#` comments and malformed lines are skipped.
pub fn parse(text: &str) -> Vec<Entry> {
    text.lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .filter_map(|l| {
            let (id, name) = l.split_once('\t')?;
            Some(Entry {
                id: id.trim().parse().ok()?,
                name: name.trim().to_string(),
            })
        })
        .collect()
}

pub fn animations() -> Vec<Entry> {
    parse(ANIMATIONS)
}

pub fn sounds() -> Vec<Entry> {
    parse(SOUNDS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipped_catalogues_parse() {
        let a = animations();
        assert!(a.len() >= 25);
        assert_eq!(
            a.iter().find(|e| e.id == 10).map(|e| e.name.as_str()),
            Some("Frustrated")
        );
        assert!(sounds().iter().any(|e| e.id == 1915));
        assert_eq!(
            parse("x\tbad\n# c\n5\tok\n"),
            vec![Entry {
                id: 5,
                name: "ok".into()
            }]
        );
    }
}
