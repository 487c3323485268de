//! Sphero Edu's sounds (`Sound.Animal.Cat.play(true)`, `playSound`) on droids that have a
//! speaker of their own, and what is said on the others.
//!
//! Sphero Edu plays its sounds on the phone or tablet running the program; droidctl has no
//! speaker of its own to play them on, so a robot without one prints which sound would play.
//! R2-D2 and R2-Q5 play clips by number (the v2 catalogue's Play Audio File; spherov2's
//! `R2D2.Audio`): a sound given by number plays that clip, and one whose name matches a clip
//! family of droidctl's sound catalogue (`assets/sounds.tsv`: `Sound.R2.Excited`,
//! `Sound.Droid.Sad`) plays the first clip of that family. Sphero publishes neither the mapping
//! of its Edu sounds to droid clips nor their lengths: the mapping by name and the length
//! ([`SOUND_SECONDS`]) are droidctl's guesses, unverified.

use crate::model::Model;

/// How long a sound lasts when a program waits for it, in seconds (unverified: Sphero
/// publishes no lengths; its effect and animal clips run about a second).
pub const SOUND_SECONDS: f64 = 1.0;

/// The catalogue of R2's clip families (`id<TAB>name`).
const CATALOGUE: &str = include_str!("../../assets/sounds.tsv");

/// The droid's clip for `sound` (a number, or an Edu name like `Animal.Cat`), on droids that
/// play clips by name: R2-D2 and R2-Q5. `None`: nothing to play, the sound is printed.
pub fn droid_clip(model: Model, sound: &str) -> Option<u16> {
    if let Ok(id) = sound.trim().parse::<u16>() {
        return Some(id);
    }
    // The catalogue is R2's clips: R2-D2's and R2-Q5's (the droids with legs).
    if !model.has_legs() {
        return None;
    }
    let wanted = sound.rsplit('.').next()?.to_ascii_lowercase();
    if wanted.is_empty() {
        return None;
    }
    CATALOGUE
        .lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .filter_map(|l| l.split_once('\t'))
        .find(|(_, name)| {
            name.split(|c: char| !c.is_ascii_alphanumeric())
                .any(|w| w.len() > 2 && w.eq_ignore_ascii_case(&wanted))
        })
        .and_then(|(id, _)| id.trim().parse().ok())
}

/// A sound as the output says it: `Animal.Cat`, a random one of a category, or any.
pub fn described(sound: &str) -> String {
    match sound {
        "" => "a random sound".to_string(),
        s if !s.contains('.') && s.parse::<u16>().is_err() && s.starts_with(char::is_uppercase) => {
            format!("a random {s} sound")
        }
        s => format!("sound {s:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn r2_plays_clips_by_number_and_by_family_the_others_print() {
        assert_eq!(droid_clip(Model::R2D2, "1915"), Some(1915));
        assert_eq!(droid_clip(Model::R2D2, "R2.Excited"), Some(2600));
        assert_eq!(droid_clip(Model::R2Q5, "Droid.sad"), Some(3484));
        assert_eq!(droid_clip(Model::R2D2, "Animal.Cat"), None);
        assert_eq!(droid_clip(Model::Bolt, "R2.Excited"), None);
        assert_eq!(described(""), "a random sound");
        assert_eq!(described("Animal"), "a random Animal sound");
        assert_eq!(described("Animal.Cat"), "sound \"Animal.Cat\"");
    }
}
