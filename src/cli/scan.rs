//! `droidctl scan`: list nearby robots droidctl can drive, strongest signal first. Only
//! devices that are really there count: heard advertising during the scan, or connected.
//! `--all` adds the rest (devices that are not robots, and the ones this computer remembers
//! but did not hear, marked `"heard": false`).
//!
//! Exits 1 with one line naming what is missing when there is no usable Bluetooth (no D-Bus
//! system bus, BlueZ not running, no adapter, adapter off, permission denied), within a few
//! seconds: every adapter call is bounded, and so is the whole command.

use super::CliError;
use crate::link::ble::{self, BleCentral, BleError, scan};
use crate::link::remote::{self, RelayAddr, RemoteDevice};
use crate::model::Model;
use clap::Args;
use std::io::{self, Write};
use std::time::Duration;

#[derive(Debug, Clone, Args)]
pub struct ScanArgs {
    /// How long to listen, in seconds (fractions allowed). `--scan-timeout` is the same, as
    /// every other command spells it.
    #[arg(
        long,
        visible_alias = "scan-timeout",
        value_name = "SECS",
        default_value = "5",
        value_parser = parse_secs
    )]
    pub timeout: Duration,
    /// One JSON object per line: name, model, model_name, address, rssi, heard.
    #[arg(long)]
    pub json: bool,
    /// Also list devices that are not supported robots, and those this computer remembers
    /// but did not hear (not in range, asleep; `"heard": false`).
    #[arg(long)]
    pub all: bool,
    /// Ask a relay on another machine (`droidctl serve`, spherov2's tcp_server) at
    /// HOST[:PORT] instead of this machine's Bluetooth.
    #[arg(long, value_name = "HOST[:PORT]")]
    pub remote: Option<crate::link::remote::RelayAddr>,
}

/// Longest scan accepted: a droid advertises several times a second, so minutes are a typo.
const MAX_SCAN: Duration = Duration::from_secs(300);

/// Time on top of the scan for getting an adapter and stopping: the whole command is bounded.
const OVERHEAD: Duration = Duration::from_secs(15);

fn parse_secs(s: &str) -> Result<Duration, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a number of seconds"))?;
    if !v.is_finite() || v <= 0.0 {
        return Err(format!("`{s}`: the timeout must be more than 0 seconds"));
    }
    // Checked before converting, which panics on what a Duration cannot hold.
    if v > MAX_SCAN.as_secs_f64() {
        return Err(format!("`{s}`: at most {} seconds", MAX_SCAN.as_secs()));
    }
    Ok(Duration::from_secs_f64(v))
}

/// Run `droidctl scan` on the system's adapter.
pub fn run(args: ScanArgs, out: &mut dyn Write) -> Result<i32, CliError> {
    if let Some(relay) = &args.remote {
        return run_remote(relay, &args, out).map_err(CliError::failure);
    }
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(|e| CliError::failure(format!("cannot start the async runtime: {e}")))?;
    let limit = args.timeout + OVERHEAD;
    let result = rt.block_on(async {
        match tokio::time::timeout(limit, async {
            let central = ble::open_central().await?;
            scan::scan_known(central.as_ref(), args.timeout, |_| false).await
        })
        .await
        {
            Ok(r) => r,
            Err(_) => Err(BleError::new(
                ble::BleErrorKind::Timeout,
                format!(
                    "the scan did not finish within {:.0} s — {}, or try `droidctl --sim`",
                    limit.as_secs_f64(),
                    ble::Os::CURRENT.check_hint()
                ),
            )),
        }
    });
    // Do not wait for anything BlueZ left running.
    rt.shutdown_background();
    let entries = result.map_err(|e| CliError::failure(e.message))?;
    report(&entries, &args, out, &mut std::io::stderr())
}

/// Scan with `central` and print: the testable core of [`run`].
pub async fn run_with(
    central: &dyn BleCentral,
    args: &ScanArgs,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<i32, CliError> {
    let entries = scan::scan_known(central, args.timeout, |_| false)
        .await
        .map_err(|e| CliError::failure(e.message))?;
    report(&entries, args, out, err)
}

fn report(
    entries: &[ble::ScanEntry],
    args: &ScanArgs,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<i32, CliError> {
    let shown: Vec<ble::ScanEntry> = entries
        .iter()
        .filter(|e| args.all || (e.is_supported() && e.heard))
        .cloned()
        .collect();
    let write_err = |e: std::io::Error| CliError::failure(format!("cannot write output: {e}"));
    if shown.is_empty() {
        // A hint, not an error: "nothing here" is a valid answer to a scan.
        let heard = entries.iter().filter(|e| e.heard).count();
        let remembered = entries.len() - heard;
        let mut others = Vec::new();
        if heard > 0 {
            others.push(format!("{heard} other device(s) heard"));
        }
        if remembered > 0 {
            others.push(format!("{remembered} remembered but not in range"));
        }
        let tail = if !others.is_empty() && !args.all {
            format!(" ({}: --all lists them)", others.join(", "))
        } else {
            String::new()
        };
        writeln!(
            err,
            "no droids found in {:.0} s{tail} — wake it (tap it or put it on its charger) and \
             keep it near",
            args.timeout.as_secs_f64()
        )
        .map_err(write_err)?;
        return Ok(0);
    }
    render(&shown, args.json, out).map_err(write_err)?;
    Ok(0)
}

/// Print a scan result as a table (or one JSON object per line, like `packet decode --json`).
pub fn render(entries: &[ble::ScanEntry], json: bool, out: &mut dyn Write) -> io::Result<()> {
    if json {
        for e in entries {
            writeln!(out, "{}", e.to_json())?;
        }
        return Ok(());
    }
    let rows = entries
        .iter()
        .map(|e| {
            vec![
                e.name.clone().unwrap_or_else(|| "(no name)".into()),
                e.model.map_or("-", Model::display_name).to_string(),
                e.id.to_string(),
                match (e.rssi, e.heard) {
                    (Some(r), _) => format!("{r} dBm"),
                    (None, true) => "connected".into(),
                    (None, false) => "not in range (remembered)".into(),
                },
            ]
        })
        .collect();
    table(&["NAME", "MODEL", "ADDRESS", "RSSI"], rows, out)
}

/// `droidctl scan --remote`: list what the relay hears (droids only unless `--all`), as a
/// table or one JSON object per line; the whole command is bounded.
fn run_remote(relay: &RelayAddr, args: &ScanArgs, out: &mut dyn Write) -> Result<i32, String> {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the async runtime: {e}"))?;
    let found = rt
        .block_on(remote::scan(relay, args.timeout))
        .map_err(|e| e.message)?;
    rt.shutdown_background();
    let shown: Vec<&RemoteDevice> = found
        .iter()
        .filter(|d| args.all || d.model.is_some())
        .collect();
    let w = |e: io::Error| format!("cannot write output: {e}");
    if shown.is_empty() {
        let others = found.len();
        let tail = if others > 0 && !args.all {
            format!(" ({others} other device(s) heard: --all lists them)")
        } else {
            String::new()
        };
        eprintln!(
            "no droids found behind the relay at {relay}{tail} — wake it (tap it or put it on \
             its charger) and keep it near the relay"
        );
        return Ok(0);
    }
    if args.json {
        for d in shown {
            writeln!(out, "{}", d.to_json()).map_err(w)?;
        }
        return Ok(0);
    }
    let rows = shown
        .iter()
        .map(|d| {
            vec![
                if d.name.is_empty() {
                    "(no name)".into()
                } else {
                    d.name.clone()
                },
                d.model.map_or("-", Model::display_name).to_string(),
                d.address.clone(),
            ]
        })
        .collect();
    table(&["NAME", "MODEL", "ADDRESS"], rows, out).map_err(w)?;
    Ok(0)
}

/// Columns padded to their widest cell, two spaces apart; the last is not padded.
fn table(header: &[&str], rows: Vec<Vec<String>>, out: &mut dyn Write) -> io::Result<()> {
    let header: Vec<String> = header.iter().map(|h| h.to_string()).collect();
    let mut widths: Vec<usize> = header.iter().map(|h| h.chars().count()).collect();
    for r in &rows {
        for (w, c) in widths.iter_mut().zip(r) {
            // As printed: a control character is one `·`.
            *w = (*w).max(c.chars().count());
        }
    }
    for r in std::iter::once(&header).chain(&rows) {
        let mut line = String::new();
        for (i, c) in r.iter().enumerate() {
            let c = &crate::printable::clean(c);
            if i + 1 == r.len() {
                line.push_str(c);
            } else {
                line.push_str(&format!("{c:<w$}  ", w = widths[i]));
            }
        }
        writeln!(out, "{line}")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan_ad(name: Option<&str>, last: u8, rssi: Option<i16>) -> ble::Advertisement {
        ble::Advertisement {
            address: ble::BleAddress([0xF1, 0, 0, 0, 0, last]),
            name: name.map(String::from),
            rssi,
        }
    }

    #[test]
    fn json_lines() {
        let s = scan::summarize(
            &[
                scan_ad(Some("D2-AAAA"), 1, Some(-70)),
                scan_ad(None, 2, None),
            ],
            true,
        );
        let mut out = Vec::new();
        render(&s, true, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines,
            [
                r#"{"name":"D2-AAAA","model":"r2d2","model_name":"R2-D2","address":"F1:00:00:00:00:01","rssi":-70,"heard":true}"#,
                r#"{"name":null,"model":null,"model_name":null,"address":"F1:00:00:00:00:02","rssi":null,"heard":false}"#,
            ]
        );
    }

    #[test]
    fn table() {
        let s = scan::summarize(
            &[
                scan_ad(Some("D2-AAAA"), 1, Some(-70)),
                scan_ad(Some("BB-1"), 2, Some(-48)),
                scan_ad(Some("D2-OLD0"), 3, None),
            ],
            false,
        );
        let mut out = Vec::new();
        render(&s, false, &mut out).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "NAME     MODEL  ADDRESS            RSSI\n\
             BB-1     BB-8   F1:00:00:00:00:02  -48 dBm\n\
             D2-AAAA  R2-D2  F1:00:00:00:00:01  -70 dBm\n\
             D2-OLD0  R2-D2  F1:00:00:00:00:03  not in range (remembered)\n"
        );
    }

    #[test]
    fn a_hostile_name_is_listed_not_obeyed() {
        let s = scan::summarize(&[scan_ad(Some("D2-\u{1b}[2J\u{7}"), 1, Some(-70))], false);
        let mut out = Vec::new();
        render(&s, false, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(
            !text.chars().any(|c| c.is_control() && c != '\n'),
            "{text:?}"
        );
        assert!(text.contains("D2-·[2J·  R2-D2"), "{text:?}");
    }

    use crate::link::ble::fake::FakeCentral;
    use crate::link::ble::{Advertisement, BleAddress, BleErrorKind};

    fn args(all: bool, json: bool) -> ScanArgs {
        ScanArgs {
            timeout: Duration::from_secs(2),
            json,
            all,
            remote: None,
        }
    }

    fn central() -> FakeCentral {
        let c = FakeCentral::new();
        let ad = |name: &str, last, rssi, after| {
            c.advertise(
                Advertisement {
                    address: BleAddress([0xC0, 0, 0, 0, 0, last]),
                    name: Some(name.into()),
                    rssi: Some(rssi),
                },
                Duration::from_millis(after),
            )
        };
        ad("D2-1A2B", 1, -70, 0);
        ad("Keyboard", 2, -40, 0);
        ad("GB-0001", 3, -55, 1500);
        // Heard only after the scan ends: not listed.
        ad("Q5-LATE", 4, -30, 5000);
        // Remembered by the computer, switched off in a drawer: only with --all.
        c.remember(
            Advertisement {
                address: BleAddress([0xC0, 0, 0, 0, 0, 5]),
                name: Some("D2-OLD0".into()),
                rssi: None,
            },
            None,
        );
        c
    }

    #[tokio::test(start_paused = true)]
    async fn lists_supported_strongest_first() {
        let (mut out, mut err) = (Vec::new(), Vec::new());
        let status = run_with(&central(), &args(false, false), &mut out, &mut err)
            .await
            .unwrap();
        assert_eq!(status, 0);
        let text = String::from_utf8(out).unwrap();
        let names: Vec<&str> = text
            .lines()
            .skip(1)
            .map(|l| l.split(' ').next().unwrap())
            .collect();
        assert_eq!(names, ["GB-0001", "D2-1A2B"]);
        assert!(err.is_empty());
    }

    #[tokio::test(start_paused = true)]
    async fn all_and_json() {
        let (mut out, mut err) = (Vec::new(), Vec::new());
        run_with(&central(), &args(true, true), &mut out, &mut err)
            .await
            .unwrap();
        let text = String::from_utf8(out).unwrap();
        let v: Vec<serde_json::Value> = text
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        assert_eq!(v.len(), 4);
        assert_eq!(v[0]["name"], "Keyboard");
        assert_eq!(v[0]["model"], serde_json::Value::Null);
        assert_eq!(v[1]["model"], "bb9e");
        assert_eq!(v[2]["model_name"], "R2-D2");
        assert_eq!(v[2]["address"], "C0:00:00:00:00:01");
        assert_eq!(v[2]["rssi"], -70);
        assert_eq!(v[2]["heard"], true);
        assert_eq!(v[3]["name"], "D2-OLD0");
        assert_eq!(v[3]["rssi"], serde_json::Value::Null);
        assert_eq!(v[3]["heard"], false);
    }

    #[tokio::test(start_paused = true)]
    async fn nothing_found_is_a_hint_not_an_error() {
        let c = FakeCentral::new();
        c.advertise(
            Advertisement {
                address: BleAddress([1; 6]),
                name: Some("TV".into()),
                rssi: Some(-60),
            },
            Duration::ZERO,
        );
        let (mut out, mut err) = (Vec::new(), Vec::new());
        let status = run_with(&c, &args(false, false), &mut out, &mut err)
            .await
            .unwrap();
        assert_eq!(status, 0);
        assert!(out.is_empty());
        let err = String::from_utf8(err).unwrap();
        assert!(
            err.starts_with("no droids found in 2 s (1 other device(s) heard"),
            "{err}"
        );
        c.remember(
            Advertisement {
                address: BleAddress([2; 6]),
                name: Some("D2-OLD0".into()),
                rssi: None,
            },
            None,
        );
        let (mut out, mut err) = (Vec::new(), Vec::new());
        run_with(&c, &args(false, false), &mut out, &mut err)
            .await
            .unwrap();
        assert!(out.is_empty(), "a remembered droid is not listed");
        let err = String::from_utf8(err).unwrap();
        assert!(
            err.starts_with(
                "no droids found in 2 s (1 other device(s) heard, 1 remembered but not in \
                 range: --all lists them)"
            ),
            "{err}"
        );
    }

    #[tokio::test(start_paused = true)]
    async fn adapter_errors_exit_1() {
        let c = FakeCentral::new();
        c.fail_scan(BleError::adapter_off());
        let (mut out, mut err) = (Vec::new(), Vec::new());
        let e = run_with(&c, &args(false, false), &mut out, &mut err)
            .await
            .unwrap_err();
        assert_eq!(e.status, 1);
        assert!(e.message.contains("bluetoothctl power on"), "{}", e.message);
        assert_eq!(BleError::adapter_off().kind, BleErrorKind::AdapterOff);
    }

    #[test]
    fn timeouts_parse() {
        assert_eq!(parse_secs("1"), Ok(Duration::from_secs(1)));
        assert_eq!(parse_secs("0.5"), Ok(Duration::from_millis(500)));
        assert!(parse_secs("0").is_err());
        assert!(parse_secs("-1").is_err());
        assert!(parse_secs("NaN").is_err());
        assert!(parse_secs("1e9").is_err());
        assert!(parse_secs("soon").is_err());
    }
}
