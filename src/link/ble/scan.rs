//! Scanning and picking a droid, over [`BleCentral`] so that sorting, filtering, model
//! detection and output are tested with fake advertisements.

use super::backend::{Advertisement, BleAddress, BleCentral};
use super::error::{BleError, BleErrorKind, Os};
use crate::model::Model;
use serde_json::json;
use std::collections::BTreeMap;
use std::io::{self, Write};
use std::time::Duration;
use tokio::time::{Instant, sleep, timeout};

/// How often a running scan looks at what the adapter has heard.
pub const SCAN_POLL: Duration = Duration::from_millis(250);

/// Bound on each adapter call during a scan, so a wedged BlueZ cannot hang `droidctl scan`.
const SCAN_OP_TIMEOUT: Duration = Duration::from_secs(3);

/// One device in a scan result.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScanEntry {
    pub name: Option<String>,
    /// `None` for devices droidctl cannot drive.
    pub model: Option<Model>,
    pub address: BleAddress,
    pub rssi: Option<i16>,
}

impl ScanEntry {
    pub fn from_advertisement(ad: &Advertisement) -> Self {
        ScanEntry {
            name: ad.name.clone(),
            model: ad.name.as_deref().and_then(Model::from_advertised_name),
            address: ad.address,
            rssi: ad.rssi,
        }
    }

    pub fn is_supported(&self) -> bool {
        self.model.is_some()
    }

    /// The name, or the address for nameless devices.
    pub fn label(&self) -> String {
        self.name
            .clone()
            .unwrap_or_else(|| self.address.to_string())
    }

    pub fn to_json(&self) -> serde_json::Value {
        json!({
            "name": self.name,
            "model": self.model.map(Model::id),
            "model_name": self.model.map(Model::display_name),
            "address": self.address.to_string(),
            "rssi": self.rssi,
        })
    }
}

/// Merge advertisements per address (the newest name and RSSI win, older ones fill gaps),
/// drop unsupported devices unless `all`, and sort strongest first (unknown RSSI last, then by
/// name and address so the order is stable).
pub fn summarize(ads: &[Advertisement], all: bool) -> Vec<ScanEntry> {
    let mut by_addr: BTreeMap<BleAddress, Advertisement> = BTreeMap::new();
    for ad in ads {
        by_addr
            .entry(ad.address)
            .and_modify(|old| {
                old.name = ad.name.clone().or(old.name.take());
                old.rssi = ad.rssi.or(old.rssi);
            })
            .or_insert_with(|| ad.clone());
    }
    let mut out: Vec<ScanEntry> = by_addr
        .values()
        .map(ScanEntry::from_advertisement)
        .filter(|e| all || e.is_supported())
        .collect();
    out.sort_by(|a, b| {
        let strength = |e: &ScanEntry| std::cmp::Reverse(e.rssi.map_or(i32::MIN, i32::from));
        strength(a)
            .cmp(&strength(b))
            .then_with(|| a.name.cmp(&b.name))
            .then_with(|| a.address.cmp(&b.address))
    });
    out
}

/// Listen for `duration` (or until `done` says enough) and return every device heard,
/// summarized with `all = true`: callers filter.
pub async fn scan(
    central: &dyn BleCentral,
    duration: Duration,
    done: impl Fn(&[ScanEntry]) -> bool,
) -> Result<Vec<ScanEntry>, BleError> {
    op("starting a scan", central.start_scan()).await?;
    let deadline = Instant::now() + duration;
    let result = async {
        loop {
            let ads = op("listing devices", central.advertisements()).await?;
            let entries = summarize(&ads, true);
            if Instant::now() >= deadline || done(&entries) {
                return Ok(entries);
            }
            sleep(SCAN_POLL.min(deadline.saturating_duration_since(Instant::now()))).await;
        }
    }
    .await;
    let _ = timeout(SCAN_OP_TIMEOUT, central.stop_scan()).await;
    result
}

/// One adapter call, bounded so a wedged BlueZ cannot hang a scan.
async fn op<T>(
    what: &str,
    f: impl std::future::Future<Output = Result<T, BleError>>,
) -> Result<T, BleError> {
    timeout(SCAN_OP_TIMEOUT, f).await.unwrap_or_else(|_| {
        Err(BleError::new(
            BleErrorKind::Timeout,
            format!(
                "{} did not answer ({what}) within {} s — {}",
                Os::CURRENT.stack(),
                SCAN_OP_TIMEOUT.as_secs(),
                Os::CURRENT.check_hint()
            ),
        ))
    })
}

/// Which droid to use.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceSelector {
    /// Advertised name (case-insensitive; a unique part of it is enough: `1A2B`).
    pub name: Option<String>,
    pub address: Option<BleAddress>,
    /// How long to scan.
    pub scan_timeout: Duration,
}

impl Default for DeviceSelector {
    fn default() -> Self {
        DeviceSelector {
            name: None,
            address: None,
            scan_timeout: Duration::from_secs(5),
        }
    }
}

impl DeviceSelector {
    /// Whether `entries` already hold what the user asked for by name or address, so the scan
    /// can stop early. "The strongest" needs the full scan to compare.
    pub fn satisfied_by(&self, entries: &[ScanEntry]) -> bool {
        match (&self.address, &self.name) {
            (Some(a), _) => entries.iter().any(|e| e.address == *a),
            (None, Some(n)) => entries.iter().any(|e| {
                e.name
                    .as_deref()
                    .is_some_and(|x| x.eq_ignore_ascii_case(n.trim()))
            }),
            (None, None) => false,
        }
    }
}

const WAKE_HINT: &str = "wake it (tap it or put it on its charger) and keep it near";

/// Choose the droid `sel` asks for from a scan (`entries` sorted strongest first, all devices).
pub fn pick<'a>(entries: &'a [ScanEntry], sel: &DeviceSelector) -> Result<&'a ScanEntry, BleError> {
    let secs = sel.scan_timeout.as_secs_f64();
    let chosen = if let Some(addr) = sel.address {
        entries.iter().find(|e| e.address == addr).ok_or_else(|| {
            BleError::new(
                BleErrorKind::NotFound,
                format!("nothing with address {addr} heard in {secs:.0} s — {WAKE_HINT}"),
            )
        })?
    } else if let Some(name) = sel.name.as_deref() {
        let name = name.trim();
        let lower = name.to_ascii_lowercase();
        let exact = entries.iter().find(|e| {
            e.name
                .as_deref()
                .is_some_and(|n| n.eq_ignore_ascii_case(name))
        });
        match exact {
            Some(e) => e,
            None => {
                let partial: Vec<&ScanEntry> = entries
                    .iter()
                    .filter(|e| {
                        e.name
                            .as_deref()
                            .is_some_and(|n| n.to_ascii_lowercase().contains(&lower))
                    })
                    .collect();
                match partial.as_slice() {
                    [one] => *one,
                    [] => {
                        return Err(BleError::new(
                            BleErrorKind::NotFound,
                            format!("no device named `{name}` heard in {secs:.0} s — {WAKE_HINT}"),
                        ));
                    }
                    many => {
                        let names: Vec<String> = many.iter().map(|e| e.label()).collect();
                        return Err(BleError::new(
                            BleErrorKind::Selection,
                            format!(
                                "`{name}` matches {}: {} — give the full name or --address",
                                many.len(),
                                names.join(", ")
                            ),
                        ));
                    }
                }
            }
        }
    } else {
        entries.iter().find(|e| e.is_supported()).ok_or_else(|| {
            BleError::new(
                BleErrorKind::NotFound,
                format!(
                    "no droid found in {secs:.0} s — {WAKE_HINT}; `droidctl scan --all` lists \
                     everything heard, `droidctl --sim` needs no droid"
                ),
            )
        })?
    };
    if chosen.model.is_none() {
        return Err(BleError::new(
            BleErrorKind::Selection,
            format!(
                "{} ({}) is not a droid droidctl knows (names start D2-, Q5-, GB-, BB-, SK-, 2B- \
                 or are `Robi 42`)",
                chosen.label(),
                chosen.address
            ),
        ));
    }
    Ok(chosen)
}

/// Print a scan result as a table (or one JSON object per line, like `packet decode --json`).
pub fn render(entries: &[ScanEntry], json: bool, out: &mut dyn Write) -> io::Result<()> {
    if json {
        for e in entries {
            writeln!(out, "{}", e.to_json())?;
        }
        return Ok(());
    }
    let rows: Vec<[String; 4]> = entries
        .iter()
        .map(|e| {
            [
                e.name.clone().unwrap_or_else(|| "(no name)".into()),
                e.model.map_or("-", Model::display_name).to_string(),
                e.address.to_string(),
                e.rssi.map_or("-".into(), |r| format!("{r} dBm")),
            ]
        })
        .collect();
    let header = ["NAME", "MODEL", "ADDRESS", "RSSI"].map(String::from);
    let mut widths = header.clone().map(|h| h.chars().count());
    for r in &rows {
        for (w, c) in widths.iter_mut().zip(r) {
            *w = (*w).max(c.chars().count());
        }
    }
    for r in std::iter::once(&header).chain(&rows) {
        writeln!(
            out,
            "{:<w0$}  {:<w1$}  {:<w2$}  {}",
            r[0],
            r[1],
            r[2],
            r[3],
            w0 = widths[0],
            w1 = widths[1],
            w2 = widths[2]
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ad(name: Option<&str>, last: u8, rssi: Option<i16>) -> Advertisement {
        Advertisement {
            address: BleAddress([0xF1, 0, 0, 0, 0, last]),
            name: name.map(String::from),
            rssi,
        }
    }

    #[test]
    fn summarize_sorts_strongest_first_and_filters() {
        let ads = [
            ad(Some("D2-AAAA"), 1, Some(-70)),
            ad(Some("JBL Flip"), 2, Some(-30)),
            ad(Some("BB-1234"), 3, Some(-50)),
            ad(Some("Q5-0001"), 4, None),
            ad(None, 5, Some(-40)),
            ad(Some("Robi 42"), 6, Some(-60)),
        ];
        let names = |v: Vec<ScanEntry>| v.into_iter().map(|e| e.label()).collect::<Vec<_>>();
        assert_eq!(
            names(summarize(&ads, false)),
            ["BB-1234", "Robi 42", "D2-AAAA", "Q5-0001"]
        );
        assert_eq!(
            names(summarize(&ads, true)),
            [
                "JBL Flip",
                "F1:00:00:00:00:05",
                "BB-1234",
                "Robi 42",
                "D2-AAAA",
                "Q5-0001"
            ]
        );
        let s = summarize(&ads, false);
        assert_eq!(s[0].model, Some(Model::BB8));
        assert_eq!(s[1].model, Some(Model::Robi42));
        assert_eq!(s[2].model, Some(Model::R2D2));
        assert_eq!(s[3].model, Some(Model::R2Q5));
    }

    #[test]
    fn summarize_merges_per_address() {
        let ads = [
            ad(Some("D2-AAAA"), 1, Some(-70)),
            ad(None, 1, Some(-40)),
            ad(Some("D2-AAAA"), 1, None),
        ];
        let s = summarize(&ads, false);
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].rssi, Some(-40));
        assert_eq!(s[0].name.as_deref(), Some("D2-AAAA"));
    }

    #[test]
    fn json_lines() {
        let s = summarize(
            &[ad(Some("D2-AAAA"), 1, Some(-70)), ad(None, 2, None)],
            true,
        );
        let mut out = Vec::new();
        render(&s, true, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines,
            [
                r#"{"name":"D2-AAAA","model":"r2d2","model_name":"R2-D2","address":"F1:00:00:00:00:01","rssi":-70}"#,
                r#"{"name":null,"model":null,"model_name":null,"address":"F1:00:00:00:00:02","rssi":null}"#,
            ]
        );
    }

    #[test]
    fn table() {
        let s = summarize(
            &[
                ad(Some("D2-AAAA"), 1, Some(-70)),
                ad(Some("BB-1"), 2, Some(-48)),
            ],
            false,
        );
        let mut out = Vec::new();
        render(&s, false, &mut out).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "NAME     MODEL  ADDRESS            RSSI\n\
             BB-1     BB-8   F1:00:00:00:00:02  -48 dBm\n\
             D2-AAAA  R2-D2  F1:00:00:00:00:01  -70 dBm\n"
        );
    }

    fn sel(name: Option<&str>, address: Option<BleAddress>) -> DeviceSelector {
        DeviceSelector {
            name: name.map(String::from),
            address,
            scan_timeout: Duration::from_secs(5),
        }
    }

    #[test]
    fn pick_strongest_name_address() {
        let all = summarize(
            &[
                ad(Some("D2-AAAA"), 1, Some(-70)),
                ad(Some("JBL Flip"), 2, Some(-30)),
                ad(Some("D2-BBBB"), 3, Some(-50)),
                ad(Some("GB-CCCC"), 4, Some(-90)),
            ],
            true,
        );
        assert_eq!(pick(&all, &sel(None, None)).unwrap().label(), "D2-BBBB");
        assert_eq!(
            pick(&all, &sel(Some("d2-aaaa"), None)).unwrap().label(),
            "D2-AAAA"
        );
        assert_eq!(
            pick(&all, &sel(Some("cccc"), None)).unwrap().label(),
            "GB-CCCC"
        );
        let a = BleAddress([0xF1, 0, 0, 0, 0, 4]);
        assert_eq!(pick(&all, &sel(None, Some(a))).unwrap().label(), "GB-CCCC");

        let e = pick(&all, &sel(Some("D2-"), None)).unwrap_err();
        assert_eq!(e.kind, BleErrorKind::Selection);
        assert!(e.message.contains("D2-BBBB, D2-AAAA"), "{e}");
        let e = pick(&all, &sel(Some("JBL Flip"), None)).unwrap_err();
        assert_eq!(e.kind, BleErrorKind::Selection);
        assert!(e.message.contains("not a droid"), "{e}");
        let e = pick(&all, &sel(Some("X-WING"), None)).unwrap_err();
        assert_eq!(e.kind, BleErrorKind::NotFound);
        let none = summarize(&[ad(Some("JBL Flip"), 2, Some(-30))], true);
        let e = pick(&none, &sel(None, None)).unwrap_err();
        assert_eq!(e.kind, BleErrorKind::NotFound);
        assert!(e.message.contains("--sim"), "{e}");
    }

    #[test]
    fn satisfied_by() {
        let all = summarize(&[ad(Some("D2-AAAA"), 1, Some(-70))], true);
        assert!(sel(Some("d2-aaaa"), None).satisfied_by(&all));
        assert!(!sel(Some("aaaa"), None).satisfied_by(&all));
        assert!(!sel(None, None).satisfied_by(&all));
        assert!(sel(None, Some(BleAddress([0xF1, 0, 0, 0, 0, 1]))).satisfied_by(&all));
    }
}
