//! The animation and sound palettes, loaded from the catalogues shipped in `assets/`: the
//! names of the ids the families play ([`super::Family::animation`], [`super::Family::sound`]).
//! Here, below the app and the bridge, because both offer them by name (the app's palettes,
//! the bridge's `animation`/`sound` commands and Home Assistant's selects, issue 40 point 5):
//! one list, never a copy.

use std::sync::OnceLock;

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
    Palette::Animations.entries().to_vec()
}

pub fn sounds() -> Vec<Entry> {
    Palette::Sounds.entries().to_vec()
}

/// One of the two palettes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Palette {
    Animations,
    Sounds,
}

impl Palette {
    /// Its entries, parsed once.
    pub fn entries(self) -> &'static [Entry] {
        static ANIMATION_ENTRIES: OnceLock<Vec<Entry>> = OnceLock::new();
        static SOUND_ENTRIES: OnceLock<Vec<Entry>> = OnceLock::new();
        match self {
            Palette::Animations => ANIMATION_ENTRIES.get_or_init(|| parse(ANIMATIONS)),
            Palette::Sounds => SOUND_ENTRIES.get_or_init(|| parse(SOUNDS)),
        }
    }

    /// The id of the entry named `name` (letter case and surrounding blanks aside).
    pub fn id_of(self, name: &str) -> Option<u16> {
        let name = name.trim();
        self.entries()
            .iter()
            .find(|e| e.name.eq_ignore_ascii_case(name))
            .map(|e| e.id)
    }

    /// The name of id `id`, when the palette has one.
    pub fn name_of(self, id: u16) -> Option<&'static str> {
        self.entries()
            .iter()
            .find(|e| e.id == id)
            .map(|e| e.name.as_str())
    }
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
        assert_eq!(Palette::Animations.id_of(" frustrated "), Some(10));
        assert_eq!(Palette::Sounds.name_of(1915), Some("R2 Burnout"));
        assert_eq!(Palette::Sounds.id_of("Frustrated"), None);
        // Names are what the bridge and Home Assistant select by: no two alike.
        for p in [Palette::Animations, Palette::Sounds] {
            for e in p.entries() {
                assert_eq!(p.id_of(&e.name), Some(e.id), "{p:?} {e:?}");
            }
        }
        assert_eq!(
            parse("x\tbad\n# c\n5\tok\n"),
            vec![Entry {
                id: 5,
                name: "ok".into()
            }]
        );
    }
}
