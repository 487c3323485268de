//! Scanning and picking a droid, over [`BleCentral`] so that sorting, filtering, model
//! detection and output are tested with fake advertisements.

use super::backend::{Advertisement, BleAddress, BleCentral, DeviceId, KnownDevice};
use super::error::{BleError, BleErrorKind, Os};
use crate::model::Model;
use serde_json::json;
use std::collections::BTreeMap;
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
    /// Who it is: what scan merging, the picker and `--address` key on.
    pub id: DeviceId,
    /// Its address, or where the platform hides it (macOS) a six-byte stand-in: for callers
    /// keyed on addresses.
    pub address: BleAddress,
    pub rssi: Option<i16>,
    /// Really there: it advertised during this scan or is connected now. A device the
    /// computer only remembers is not.
    pub heard: bool,
}

impl ScanEntry {
    pub fn from_device(d: &KnownDevice) -> Self {
        ScanEntry {
            name: d.name.clone(),
            model: d.name.as_deref().and_then(Model::from_advertised_name),
            address: d.id.stand_in(),
            id: d.id.clone(),
            rssi: d.rssi,
            heard: d.heard(),
        }
    }

    pub fn from_advertisement(ad: &Advertisement) -> Self {
        ScanEntry::from_device(&KnownDevice::from(ad))
    }

    pub fn is_supported(&self) -> bool {
        self.model.is_some()
    }

    /// A droid this build can drive.
    pub fn is_drivable(&self) -> bool {
        self.model.is_some_and(Model::drivable)
    }

    /// The name, or the id for nameless devices.
    pub fn label(&self) -> String {
        self.name.clone().unwrap_or_else(|| self.id.to_string())
    }

    pub fn to_json(&self) -> serde_json::Value {
        json!({
            "name": self.name,
            "model": self.model.map(Model::id),
            "model_name": self.model.map(Model::display_name),
            "address": self.id.to_string(),
            "rssi": self.rssi,
            "heard": self.heard,
        })
    }
}

/// Merge what the adapter reported per device (the newest name and RSSI win, older ones fill
/// gaps; heard once is heard), drop unsupported devices unless `all`, and sort: heard before
/// remembered, strongest first (unknown RSSI last), then by name and id so the order is
/// stable.
pub fn summarize_devices(devices: &[KnownDevice], all: bool) -> Vec<ScanEntry> {
    let mut by_id: BTreeMap<&DeviceId, KnownDevice> = BTreeMap::new();
    for d in devices {
        by_id
            .entry(&d.id)
            .and_modify(|old| {
                old.name = d.name.clone().or(old.name.take());
                old.rssi = d.rssi.or(old.rssi);
                old.connected |= d.connected;
            })
            .or_insert_with(|| d.clone());
    }
    let mut out: Vec<ScanEntry> = by_id
        .values()
        .map(ScanEntry::from_device)
        .filter(|e| all || e.is_supported())
        .collect();
    out.sort_by(|a, b| {
        let strength = |e: &ScanEntry| std::cmp::Reverse(e.rssi.map_or(i32::MIN, i32::from));
        b.heard
            .cmp(&a.heard)
            .then_with(|| strength(a).cmp(&strength(b)))
            .then_with(|| a.name.cmp(&b.name))
            .then_with(|| a.id.cmp(&b.id))
    });
    out
}

/// [`summarize_devices`] for advertisements by address (an advertisement without an RSSI is
/// a remembered device, not heard).
pub fn summarize(ads: &[Advertisement], all: bool) -> Vec<ScanEntry> {
    let devices: Vec<KnownDevice> = ads.iter().map(KnownDevice::from).collect();
    summarize_devices(&devices, all)
}

/// Listen for `duration` (or until `done` says enough of what was heard) and return every
/// device heard, summarized with `all = true`: callers filter. Devices the adapter only
/// remembers are left out ([`scan_known`] keeps them).
pub async fn scan(
    central: &dyn BleCentral,
    duration: Duration,
    done: impl Fn(&[ScanEntry]) -> bool,
) -> Result<Vec<ScanEntry>, BleError> {
    let mut entries = scan_known(central, duration, done).await?;
    entries.retain(|e| e.heard);
    Ok(entries)
}

/// [`scan`], keeping the devices the adapter remembers but did not hear (`heard: false`,
/// last). `done` sees only the heard ones: a remembered droid may still wake up and be
/// heard before the scan ends.
pub async fn scan_known(
    central: &dyn BleCentral,
    duration: Duration,
    done: impl Fn(&[ScanEntry]) -> bool,
) -> Result<Vec<ScanEntry>, BleError> {
    op("starting a scan", central.start_scan()).await?;
    let deadline = Instant::now() + duration;
    let result = async {
        loop {
            let devices = op("listing devices", central.devices()).await?;
            let entries = summarize_devices(&devices, true);
            let heard = entries.iter().take_while(|e| e.heard).count();
            if Instant::now() >= deadline || done(&entries[..heard]) {
                return Ok(entries);
            }
            sleep(SCAN_POLL.min(deadline.saturating_duration_since(Instant::now()))).await;
        }
    }
    .await;
    let _ = timeout(SCAN_OP_TIMEOUT, central.stop_scan()).await;
    // Switched off while listening: that, not "nothing heard", is the news.
    if let Ok(Ok(false)) = timeout(SCAN_OP_TIMEOUT, central.powered()).await {
        return Err(BleError::adapter_off_on(Os::CURRENT));
    }
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
    /// `--address`: a Bluetooth address, or the platform's identifier for the device (the
    /// UUID macOS gives it), any case; see [`DeviceId::matches`].
    pub address: Option<String>,
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

/// Whether `entry`'s name is `name` (case-insensitive).
fn named(entry: &ScanEntry, name: &str) -> bool {
    entry
        .name
        .as_deref()
        .is_some_and(|x| x.eq_ignore_ascii_case(name.trim()))
}

impl DeviceSelector {
    /// Whether `heard` already holds what the user asked for by name or address, so the scan
    /// can stop early. "The strongest" needs the full scan to compare.
    pub fn satisfied_by(&self, heard: &[ScanEntry]) -> bool {
        let heard = heard.iter().filter(|e| e.heard);
        match (&self.address, &self.name) {
            (Some(a), _) => heard.into_iter().any(|e| e.id.matches(a)),
            (None, Some(n)) => heard.into_iter().any(|e| named(e, n)),
            (None, None) => false,
        }
    }
}

const WAKE_HINT: &str = "wake it (tap it or put it on its charger) and keep it near";

/// The one line for a droid this computer remembers that did not answer the scan.
fn not_in_range(e: &ScanEntry, secs: f64) -> BleError {
    BleError::new(
        BleErrorKind::NotFound,
        format!(
            "{} ({}) is known to this computer but not in range: not heard in {secs:.0} s — \
             {WAKE_HINT}, and close any phone app holding it",
            e.label(),
            e.id
        ),
    )
}

/// Choose the droid `sel` asks for from a scan (`entries` sorted heard and strongest first,
/// all devices, remembered ones included with `heard: false`). Only heard devices are
/// chosen; a name or address that matches only a remembered one says so.
pub fn pick<'a>(entries: &'a [ScanEntry], sel: &DeviceSelector) -> Result<&'a ScanEntry, BleError> {
    let secs = sel.scan_timeout.as_secs_f64();
    let (heard, remembered): (Vec<&ScanEntry>, Vec<&ScanEntry>) =
        entries.iter().partition(|e| e.heard);
    let chosen = if let Some(addr) = sel.address.as_deref() {
        match heard.iter().find(|e| e.id.matches(addr)) {
            Some(e) => *e,
            None => {
                if let Some(e) = remembered.iter().find(|e| e.id.matches(addr)) {
                    return Err(not_in_range(e, secs));
                }
                return Err(BleError::new(
                    BleErrorKind::NotFound,
                    format!(
                        "nothing with address {} heard in {secs:.0} s — {WAKE_HINT}",
                        addr.trim()
                    ),
                ));
            }
        }
    } else if let Some(name) = sel.name.as_deref() {
        let name = name.trim();
        match find_named(&heard, name)? {
            Some(e) => e,
            None => {
                if let Ok(Some(e)) = find_named(&remembered, name) {
                    return Err(not_in_range(e, secs));
                }
                return Err(BleError::new(
                    BleErrorKind::NotFound,
                    format!("no device named `{name}` heard in {secs:.0} s — {WAKE_HINT}"),
                ));
            }
        }
    } else {
        match heard.iter().find(|e| e.is_drivable()) {
            Some(e) => *e,
            None => {
                let known: Vec<String> = remembered
                    .iter()
                    .filter(|e| e.is_drivable())
                    .map(|e| e.label())
                    .collect();
                let known = if known.is_empty() {
                    String::new()
                } else {
                    format!(
                        " ({} known to this computer but not in range)",
                        known.join(", ")
                    )
                };
                return Err(BleError::new(
                    BleErrorKind::NotFound,
                    format!(
                        "no droid found in {secs:.0} s{known} — {WAKE_HINT}; `droidctl scan \
                         --all` lists everything heard, `droidctl --sim` needs no droid"
                    ),
                ));
            }
        }
    };
    if chosen.model.is_none() {
        return Err(BleError::new(
            BleErrorKind::Selection,
            format!(
                "{} ({}) is not a droid droidctl knows (names start D2-, Q5-, GB-, BB-, SK-, 2B- \
                 or are `Robi 42`)",
                chosen.label(),
                chosen.id
            ),
        ));
    }
    Ok(chosen)
}

/// The entry named `name` among `entries`: exactly (case-insensitive), else the only one
/// whose name contains it. More than one is an error.
fn find_named<'a>(
    entries: &[&'a ScanEntry],
    name: &str,
) -> Result<Option<&'a ScanEntry>, BleError> {
    if let Some(e) = entries.iter().find(|e| named(e, name)) {
        return Ok(Some(*e));
    }
    let lower = name.to_ascii_lowercase();
    let partial: Vec<&ScanEntry> = entries
        .iter()
        .copied()
        .filter(|e| {
            e.name
                .as_deref()
                .is_some_and(|n| n.to_ascii_lowercase().contains(&lower))
        })
        .collect();
    match partial.as_slice() {
        [] => Ok(None),
        [one] => Ok(Some(*one)),
        many => {
            let names: Vec<String> = many.iter().map(|e| e.label()).collect();
            Err(BleError::new(
                BleErrorKind::Selection,
                format!(
                    "`{name}` matches {}: {} — give the full name or --address",
                    many.len(),
                    names.join(", ")
                ),
            ))
        }
    }
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
    fn summarize_sorts_heard_and_strongest_first_and_filters() {
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
        // No RSSI: remembered, not heard.
        assert!(s[..3].iter().all(|e| e.heard));
        assert!(!s[3].heard);
    }

    #[test]
    fn summarize_merges_per_device() {
        let ads = [
            ad(Some("D2-AAAA"), 1, Some(-70)),
            ad(None, 1, Some(-40)),
            ad(Some("D2-AAAA"), 1, None),
        ];
        let s = summarize(&ads, false);
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].rssi, Some(-40));
        assert_eq!(s[0].name.as_deref(), Some("D2-AAAA"));
        assert!(s[0].heard);
    }

    /// CoreBluetooth gives every device the address 00:00:00:00:00:00: the platform's
    /// identifier keeps them apart.
    #[test]
    fn the_same_address_is_two_devices_with_two_identifiers() {
        let dev = |key: &str, name: &str, rssi| KnownDevice {
            id: DeviceId::new(key, Some(BleAddress::default())),
            name: Some(name.into()),
            rssi: Some(rssi),
            connected: false,
        };
        let s = summarize_devices(
            &[
                dev("8e5b5b4e-1234-4a6b-9c8d-0123456789ab", "D2-AAAA", -50),
                dev("0f000000-1234-4a6b-9c8d-0123456789ab", "D2-BBBB", -60),
            ],
            false,
        );
        assert_eq!(s.len(), 2);
        assert_eq!(s[0].id.to_string(), "8e5b5b4e-1234-4a6b-9c8d-0123456789ab");
        let by = |a: &str| sel_addr(a);
        assert_eq!(
            pick(&s, &by("0F000000-1234-4A6B-9C8D-0123456789AB"))
                .unwrap()
                .label(),
            "D2-BBBB"
        );
    }

    fn sel_addr(a: &str) -> DeviceSelector {
        DeviceSelector {
            address: Some(a.into()),
            ..DeviceSelector::default()
        }
    }

    fn sel(name: Option<&str>, address: Option<&str>) -> DeviceSelector {
        DeviceSelector {
            name: name.map(String::from),
            address: address.map(String::from),
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
        assert_eq!(
            pick(&all, &sel(None, Some("f1-00-00-00-00-04")))
                .unwrap()
                .label(),
            "GB-CCCC"
        );

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

    /// BlueZ lists the droids it remembers, heard or not: only heard ones are picked, and
    /// asking for a remembered one by name or address says it is not in range.
    #[test]
    fn remembered_droids_are_neither_picked_nor_connected_to() {
        let all = summarize(
            &[
                ad(Some("D2-GONE"), 1, None),
                ad(Some("BB-HERE"), 2, Some(-80)),
            ],
            true,
        );
        assert_eq!(pick(&all, &sel(None, None)).unwrap().label(), "BB-HERE");
        for s in [
            sel(Some("d2-gone"), None),
            sel(Some("GONE"), None),
            sel(None, Some("F1:00:00:00:00:01")),
        ] {
            let e = pick(&all, &s).unwrap_err();
            assert_eq!(e.kind, BleErrorKind::NotFound, "{s:?}");
            assert_eq!(
                e.message,
                "D2-GONE (F1:00:00:00:00:01) is known to this computer but not in range: not \
                 heard in 5 s — wake it (tap it or put it on its charger) and keep it near, and \
                 close any phone app holding it"
            );
        }
        let only_remembered = summarize(&[ad(Some("D2-GONE"), 1, None)], true);
        let e = pick(&only_remembered, &sel(None, None)).unwrap_err();
        assert!(
            e.message.starts_with(
                "no droid found in 5 s (D2-GONE known to this computer but not in range)"
            ),
            "{e}"
        );
        // A remembered match does not end the scan early: it may still wake up.
        assert!(!sel(Some("D2-GONE"), None).satisfied_by(&all));
    }

    #[test]
    fn satisfied_by() {
        let all = summarize(&[ad(Some("D2-AAAA"), 1, Some(-70))], true);
        assert!(sel(Some("d2-aaaa"), None).satisfied_by(&all));
        assert!(!sel(Some("aaaa"), None).satisfied_by(&all));
        assert!(!sel(None, None).satisfied_by(&all));
        assert!(sel(None, Some("F1:00:00:00:00:01")).satisfied_by(&all));
    }
}
