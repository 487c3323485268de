//! A droid's MQTT topic level: its name made safe for a topic, and distinct from every other
//! droid's (of this bridge, and of those live on the broker already).

/// The MQTT topic level of a droid's name: letters, digits, `-` and `_` kept, anything else
/// (spaces, `/`, `+`, `#`) becomes `-` (`Robi 42` → `Robi-42`).
pub fn topic_name(name: &str) -> String {
    let t: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '-'
            }
        })
        .collect();
    if t.is_empty() { "droid".into() } else { t }
}

/// Each droid's topic level, distinct (issue 26 point 7): [`topic_name`], and when an
/// earlier droid has it already (two robots both called `Robi 42`), `-2`, `-3` … added:
/// two droids never share a topic.
pub fn topic_names(names: &[String]) -> Vec<String> {
    topic_names_besides(names, &Default::default())
}

/// [`topic_names`], none of them one of `taken` (lowercase: live on the broker already).
pub fn topic_names_besides(
    names: &[String],
    taken: &std::collections::HashSet<String>,
) -> Vec<String> {
    let mut taken = taken.clone();
    let mut out = Vec::with_capacity(names.len());
    for n in names {
        let base = topic_name(n);
        let mut t = base.clone();
        let mut k = 2usize;
        while !taken.insert(t.to_lowercase()) {
            t = format!("{base}-{k}");
            k += 1;
        }
        out.push(t);
    }
    out
}

/// The topic of droid topic-name `t`'s `leaf`.
pub fn topic(prefix: &str, t: &str, leaf: &str) -> String {
    format!("{prefix}/{t}/{leaf}")
}
