//! Why Bluetooth did not work, as a kind the code can act on and one line a person can act on.
//!
//! Most machines that run droidctl without a droid have no Bluetooth at all (containers, CI,
//! servers): each way of "no Bluetooth" gets its own message saying what is missing, what to do,
//! and that `--sim` works without a radio.
//!
//! Each platform's stack reports failures its own way: BlueZ as D-Bus error names
//! ([`BleError::from_dbus`]), CoreBluetooth as `CBManagerState`s and localized descriptions,
//! WinRT as HRESULTs. [`BleError::from_platform_text`] maps the text btleplug gives on each
//! ([`Os`]) to the same kinds and the same kind of message; it is a pure function, so every
//! platform's mapping is tested on any of them.

use crate::link::LinkError;
use std::fmt;

/// What went wrong, coarse enough to decide between "give up" and "retry".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BleErrorKind {
    /// No D-Bus system bus to reach BlueZ through (containers, minimal systems).
    NoSystemBus,
    /// The system bus is there but BlueZ (`bluetoothd`) is not.
    BluezNotRunning,
    /// BlueZ runs but there is no adapter (or the platform reports no Bluetooth LE at all).
    NoAdapter,
    /// The adapter is powered off, blocked by rfkill, or disabled (airplane mode).
    AdapterOff,
    /// BlueZ refused us (policy, group membership); macOS has not allowed this terminal app
    /// Bluetooth; Windows denied access.
    PermissionDenied,
    /// No (matching) device was heard, or BlueZ forgot it.
    NotFound,
    /// An operation took too long (droid asleep, out of range, radio busy).
    Timeout,
    /// The connection attempt failed or was aborted (`le-connection-abort-by-local`, …).
    ConnectFailed,
    /// The device is not connected (any more).
    Disconnected,
    /// The device lacks a characteristic the model's profile needs: wrong device or model.
    MissingCharacteristic,
    /// The user asked for something that cannot work (unknown name, not a droid).
    Selection,
    /// Anything else BlueZ reported.
    Other,
}

impl BleErrorKind {
    /// Whether retrying can never help, so a reconnecting session should give up.
    pub fn is_fatal(self) -> bool {
        matches!(
            self,
            BleErrorKind::NoSystemBus
                | BleErrorKind::BluezNotRunning
                | BleErrorKind::NoAdapter
                | BleErrorKind::AdapterOff
                | BleErrorKind::PermissionDenied
                | BleErrorKind::MissingCharacteristic
                | BleErrorKind::Selection
        )
    }
}

/// Whose Bluetooth stack a failure comes from, and so whose fixes the message names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Os {
    /// BlueZ over D-Bus (also what any other Unix would use).
    Linux,
    /// CoreBluetooth.
    MacOs,
    /// WinRT (`Windows.Devices.Bluetooth`).
    Windows,
}

impl Os {
    /// The platform this program was built for.
    pub const CURRENT: Os = if cfg!(target_os = "macos") {
        Os::MacOs
    } else if cfg!(windows) {
        Os::Windows
    } else {
        Os::Linux
    };

    /// The Bluetooth stack's name, for messages.
    pub fn stack(self) -> &'static str {
        match self {
            Os::Linux => "BlueZ",
            Os::MacOs => "CoreBluetooth",
            Os::Windows => "Windows Bluetooth",
        }
    }

    /// What to look at when the stack does not answer.
    pub fn check_hint(self) -> &'static str {
        match self {
            Os::Linux => "check `systemctl status bluetooth`",
            Os::MacOs => "check that Bluetooth is on (System Settings → Bluetooth)",
            Os::Windows => "check that Bluetooth is on (Settings → Bluetooth & devices)",
        }
    }
}

/// A Bluetooth failure: a kind for code, a one-line message for people.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BleError {
    pub kind: BleErrorKind,
    pub message: String,
}

impl fmt::Display for BleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for BleError {}

impl From<BleError> for LinkError {
    fn from(e: BleError) -> Self {
        LinkError {
            fatal: e.fatal(),
            message: e.message,
        }
    }
}

impl BleError {
    pub fn new(kind: BleErrorKind, message: impl Into<String>) -> Self {
        // One line, whatever BlueZ put in its message.
        let message: String = message.into();
        let message = message.split_whitespace().collect::<Vec<_>>().join(" ");
        BleError { kind, message }
    }

    /// Retrying cannot help: the session gives up instead of looping.
    pub fn fatal(&self) -> bool {
        self.kind.is_fatal()
    }

    pub fn no_system_bus(detail: &str) -> Self {
        let detail = if detail.is_empty() {
            String::new()
        } else {
            format!(" ({detail})")
        };
        BleError::new(
            BleErrorKind::NoSystemBus,
            format!(
                "no D-Bus system bus, so no BlueZ{detail} — run on a host with BlueZ running \
                 (`systemctl status bluetooth`), not a bare container, or try `droidctl --sim`"
            ),
        )
    }

    pub fn bluez_not_running() -> Self {
        BleError::new(
            BleErrorKind::BluezNotRunning,
            "BlueZ (bluetoothd) is not running — start it with `sudo systemctl start bluetooth`, \
             or try `droidctl --sim`",
        )
    }

    /// No adapter, in BlueZ's words ([`BleError::no_adapter_on`] for other platforms).
    pub fn no_adapter() -> Self {
        BleError::no_adapter_on(Os::Linux)
    }

    /// The adapter is off, in BlueZ's words ([`BleError::adapter_off_on`] for other platforms).
    pub fn adapter_off() -> Self {
        BleError::adapter_off_on(Os::Linux)
    }

    /// BlueZ refused us ([`BleError::permission_denied_on`] for other platforms).
    pub fn permission_denied() -> Self {
        BleError::permission_denied_on(Os::Linux)
    }

    pub fn no_adapter_on(os: Os) -> Self {
        BleError::new(
            BleErrorKind::NoAdapter,
            match os {
                Os::Linux => {
                    "no Bluetooth adapter found — plug one in (check `bluetoothctl list`), or try \
                     `droidctl --sim`"
                }
                Os::MacOs => {
                    "this Mac reports no Bluetooth LE — check System Information → Bluetooth, \
                     or try `droidctl --sim`"
                }
                Os::Windows => {
                    "no Bluetooth adapter found — plug one in (Bluetooth 4.0 LE or later; check \
                     Device Manager → Bluetooth), or try `droidctl --sim`"
                }
            },
        )
    }

    pub fn adapter_off_on(os: Os) -> Self {
        BleError::new(
            BleErrorKind::AdapterOff,
            match os {
                Os::Linux => {
                    "the Bluetooth adapter is off — run `bluetoothctl power on` (and `rfkill \
                     unblock bluetooth` if it is blocked), or try `droidctl --sim`"
                }
                Os::MacOs => {
                    "Bluetooth is off — turn it on in System Settings → Bluetooth (or Control \
                     Center), or try `droidctl --sim`"
                }
                Os::Windows => {
                    "Bluetooth is off — turn it on in Settings → Bluetooth & devices (and turn \
                     airplane mode off), or try `droidctl --sim`"
                }
            },
        )
    }

    pub fn permission_denied_on(os: Os) -> Self {
        BleError::new(
            BleErrorKind::PermissionDenied,
            match os {
                Os::Linux => {
                    "permission denied by BlueZ — add yourself to the `bluetooth` group (`sudo \
                     usermod -aG bluetooth $USER`, then log in again), or try `droidctl --sim`"
                }
                Os::MacOs => {
                    "macOS has not allowed this terminal app to use Bluetooth — allow it in \
                     System Settings → Privacy & Security → Bluetooth, restart the terminal, or \
                     try `droidctl --sim`"
                }
                Os::Windows => {
                    "Windows denied access to Bluetooth — let apps control radios (Settings → \
                     Privacy & security → Radios) and close other apps connected to the droid, \
                     or try `droidctl --sim`"
                }
            },
        )
    }

    /// The stack reports Bluetooth neither on nor off, and it stayed so. CoreBluetooth says
    /// that when this terminal app is not allowed Bluetooth (or the Mac has none); Windows
    /// when the radio is disabled (airplane mode, a hardware switch, its driver).
    pub fn unavailable_on(os: Os) -> Self {
        match os {
            Os::Linux => BleError::adapter_off_on(os),
            Os::MacOs => BleError::new(
                BleErrorKind::PermissionDenied,
                "Bluetooth is not available to this terminal app — allow it in System Settings \
                 → Privacy & Security → Bluetooth and check that Bluetooth is on, or try \
                 `droidctl --sim`",
            ),
            Os::Windows => BleError::new(
                BleErrorKind::AdapterOff,
                "the Bluetooth radio is disabled (airplane mode, a hardware switch or its \
                 driver) — turn Bluetooth on in Settings → Bluetooth & devices, or try \
                 `droidctl --sim`",
            ),
        }
    }

    /// The stack forgot the device (it went out of range or to sleep since the scan).
    pub fn device_gone_on(os: Os) -> Self {
        BleError::new(
            BleErrorKind::NotFound,
            format!(
                "{} no longer knows the device — scan again (is the droid awake?)",
                os.stack()
            ),
        )
    }

    pub fn timeout(what: &str, secs: f64) -> Self {
        BleError::new(
            BleErrorKind::Timeout,
            format!(
                "{what} timed out after {secs:.0} s — is the droid awake and near? tap it or put \
                 it on its charger"
            ),
        )
    }

    /// Map a D-Bus error (name and message) from BlueZ or the bus itself.
    ///
    /// The names are the stable part: BlueZ documents its `org.bluez.Error.*` names, while
    /// messages vary between versions, so only `Failed` looks at the message.
    pub fn from_dbus(name: Option<&str>, message: &str) -> Self {
        let name = name.unwrap_or("");
        let short = name.rsplit('.').next().unwrap_or(name);
        let bluez = name.starts_with("org.bluez.Error.");
        let bus = name.starts_with("org.freedesktop.DBus.Error.");
        let lower = message.to_ascii_lowercase();
        match short {
            "FileNotFound" | "NoServer" | "Disconnected" | "BadAddress" if bus => {
                BleError::no_system_bus(message)
            }
            "ServiceUnknown" | "NameHasNoOwner" if bus => BleError::bluez_not_running(),
            "AccessDenied" | "AuthFailed" | "InteractiveAuthorizationRequired" if bus => {
                BleError::permission_denied_on(Os::Linux)
            }
            "NotPermitted" | "NotAuthorized" if bluez => BleError::permission_denied_on(Os::Linux),
            "NotReady" if bluez => BleError::adapter_off_on(Os::Linux),
            "UnknownObject" | "UnknownMethod" if bus => BleError::new(
                BleErrorKind::NotFound,
                "BlueZ no longer knows the device — scan again (is the droid awake?)",
            ),
            "DoesNotExist" if bluez => BleError::new(
                BleErrorKind::NotFound,
                "BlueZ no longer knows the device — scan again (is the droid awake?)",
            ),
            "NoReply" | "Timeout" | "TimedOut" if bus => BleError::new(
                BleErrorKind::Timeout,
                "BlueZ did not answer in time — is the droid awake and near? tap it or put it \
                 on its charger",
            ),
            "NotConnected" if bluez => {
                BleError::new(BleErrorKind::Disconnected, "the droid is not connected")
            }
            "InProgress" | "AlreadyConnected" if bluez => BleError::new(
                BleErrorKind::ConnectFailed,
                format!("BlueZ is busy with this device ({message}) — retrying"),
            ),
            "Failed" | "AuthenticationCanceled" | "ConnectionAttemptFailed" if bluez => {
                if lower.contains("abort") || lower.contains("connection-") {
                    BleError::new(
                        BleErrorKind::ConnectFailed,
                        format!(
                            "the connection was aborted ({message}) — wake the droid; if it \
                             keeps happening run `bluetoothctl remove ADDRESS` and scan again"
                        ),
                    )
                } else if lower.contains("not connected") {
                    BleError::new(BleErrorKind::Disconnected, "the droid is not connected")
                } else {
                    BleError::new(BleErrorKind::ConnectFailed, format!("BlueZ: {message}"))
                }
            }
            _ => {
                let shown = if message.is_empty() { name } else { message };
                BleError::new(BleErrorKind::Other, format!("Bluetooth error: {shown}"))
            }
        }
    }

    /// Map the text of a btleplug error from `os`'s backend: its `Display`, or for BlueZ the
    /// `Debug` rendering that carries the D-Bus error name (`D-Bus error: MESSAGE (NAME)`).
    ///
    /// What each backend reports (btleplug 0.11–0.13):
    /// - Linux (BlueZ): D-Bus errors ([`BleError::from_dbus`]) and a few texts of its own.
    /// - macOS (CoreBluetooth): `Permission denied` when this terminal app was refused
    ///   Bluetooth; `Runtime Error: …` with `NSError`'s localized description (`The connection
    ///   has failed unexpectedly.`, `The specified device has disconnected from us.`, …);
    ///   adapter states (`poweredOff`, `unauthorized`, `unsupported`) in other tools' texts.
    /// - Windows (WinRT): `Error { code: HRESULT(0x800710DF), message: "…" }`; the message is
    ///   localized, so the HRESULT decides.
    pub fn from_platform_text(os: Os, text: &str) -> Self {
        if let Some((name, message)) = dbus_error_in(text) {
            return BleError::from_dbus(Some(&name), &message);
        }
        let lower = text.to_ascii_lowercase();
        // btleplug's own texts, the same on every platform.
        if lower.contains("permission denied") {
            return BleError::permission_denied_on(os);
        }
        if lower.contains("no bluetooth adapter") {
            return BleError::no_adapter_on(os);
        }
        let mapped = match os {
            Os::Linux => from_bluez_text(text, &lower),
            Os::MacOs => from_corebluetooth_text(text, &lower),
            Os::Windows => from_winrt_text(text, &lower),
        };
        mapped.unwrap_or_else(|| {
            BleError::new(BleErrorKind::Other, format!("Bluetooth error: {text}"))
        })
    }
}

fn from_bluez_text(text: &str, lower: &str) -> Option<BleError> {
    if lower.contains("service discovery timed out") {
        Some(BleError::new(
            BleErrorKind::Timeout,
            "service discovery timed out — is the droid awake and near? tap it or put it on its \
             charger",
        ))
    } else if lower.contains("not found") && lower.contains("uuid") {
        Some(BleError::new(BleErrorKind::MissingCharacteristic, text))
    } else {
        None
    }
}

fn from_corebluetooth_text(text: &str, lower: &str) -> Option<BleError> {
    let has = |words: &[&str]| words.iter().any(|w| lower.contains(w));
    let os = Os::MacOs;
    let detail = text.strip_prefix("Runtime Error: ").unwrap_or(text);
    Some(if has(&["unauthorized", "not authorized"]) {
        BleError::permission_denied_on(os)
    } else if has(&[
        "poweredoff",
        "powered off",
        "not powered on",
        "bluetooth is off",
    ]) {
        BleError::adapter_off_on(os)
    } else if has(&["unsupported"]) {
        BleError::no_adapter_on(os)
    } else if has(&["adapter failed to connect"]) {
        // CoreBluetooth never reported a state: the permission prompt went unanswered, or the
        // Bluetooth daemon is stuck.
        BleError::unavailable_on(os)
    } else if has(&["peer removed pairing"]) {
        BleError::new(
            BleErrorKind::ConnectFailed,
            "the droid forgot its pairing with this Mac — remove it in System Settings → \
             Bluetooth and scan again",
        )
    } else if has(&["not connected"]) {
        BleError::new(BleErrorKind::Disconnected, "the droid is not connected")
    } else if has(&["disconnected"]) {
        BleError::new(BleErrorKind::Disconnected, "the droid disconnected")
    } else if has(&["timed out"]) {
        BleError::new(
            BleErrorKind::Timeout,
            format!(
                "the connection timed out ({detail}) — is the droid awake and near? tap it or \
                 put it on its charger"
            ),
        )
    } else if has(&[
        "connection has failed",
        "failed to connect",
        "was cancelled",
    ]) {
        BleError::new(
            BleErrorKind::ConnectFailed,
            format!("the connection failed ({detail}) — wake the droid and try again"),
        )
    } else if has(&["no longer available", "unknown device"]) {
        BleError::device_gone_on(os)
    } else {
        return None;
    })
}

/// The HRESULT in a `windows::core::Error` rendering (`HRESULT(0x800710DF)`).
fn hresult_in(text: &str) -> Option<u32> {
    const MARK: &str = "HRESULT(0x";
    let rest = &text[text.find(MARK)? + MARK.len()..];
    let hex = &rest[..rest.find(')')?];
    u32::from_str_radix(hex, 16).ok()
}

fn from_winrt_text(text: &str, lower: &str) -> Option<BleError> {
    let os = Os::Windows;
    let Some(code) = hresult_in(text) else {
        return lower
            .contains("not connected")
            .then(|| BleError::new(BleErrorKind::Disconnected, "the droid is not connected"));
    };
    Some(match code {
        // ERROR_DEVICE_NOT_AVAILABLE, what scanning with the radio off gives; ERROR_NOT_READY.
        0x8007_10DF | 0x8007_0015 => BleError::adapter_off_on(os),
        // E_ACCESSDENIED.
        0x8007_0005 => BleError::permission_denied_on(os),
        // E_NOINTERFACE: a Windows too old for the Bluetooth LE API.
        0x8000_4002 => BleError::new(
            BleErrorKind::NoAdapter,
            "this Windows lacks the Bluetooth LE interface droidctl needs (Windows 10 version \
             1803 or later) — update Windows, or try `droidctl --sim`",
        ),
        // ERROR_DEVICE_NOT_CONNECTED; RO_E_CLOSED (the connection's objects were closed).
        0x8007_048F | 0x8000_0013 => {
            BleError::new(BleErrorKind::Disconnected, "the droid is not connected")
        }
        // ERROR_TIMEOUT; ERROR_SEM_TIMEOUT.
        0x8007_05B4 | 0x8007_0079 => BleError::new(
            BleErrorKind::Timeout,
            "Windows Bluetooth timed out — is the droid awake and near? tap it or put it on its \
             charger",
        ),
        // ERROR_NOT_FOUND.
        0x8007_0490 => BleError::device_gone_on(os),
        // ERROR_GEN_FAILURE, E_UNEXPECTED, E_ABORT: the connection attempt went wrong.
        0x8007_001F | 0x8000_FFFF | 0x8000_4004 => BleError::new(
            BleErrorKind::ConnectFailed,
            format!(
                "the connection failed (HRESULT 0x{code:08X}) — wake the droid; if it keeps \
                 happening remove it under Settings → Bluetooth & devices and scan again"
            ),
        ),
        _ => return None,
    })
}

/// Find `D-Bus error: MESSAGE (NAME)` in a `Debug` rendering; returns (name, message).
pub(crate) fn dbus_error_in(debug: &str) -> Option<(String, String)> {
    let rest = &debug[debug.find(DBUS_MARK)? + DBUS_MARK.len()..];
    let open = rest.rfind(" (")?;
    let after = &rest[open + 2..];
    let name = &after[..after.find(')')?];
    if !name.contains('.') || name.contains(' ') {
        return None;
    }
    Some((name.to_string(), rest[..open].to_string()))
}

/// How the `dbus` crate's `Debug` introduces an error.
pub(crate) const DBUS_MARK: &str = "D-Bus error: ";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_bluetooth_messages_name_the_fix_and_sim() {
        for e in [
            BleError::no_system_bus("no socket"),
            BleError::bluez_not_running(),
            BleError::no_adapter(),
            BleError::adapter_off(),
            BleError::permission_denied(),
        ] {
            assert!(e.fatal(), "{e}");
            assert!(e.message.contains("`droidctl --sim`"), "{e}");
            assert!(!e.message.contains('\n'), "{e}");
        }
        assert_eq!(
            BleError::no_adapter().message,
            "no Bluetooth adapter found — plug one in (check `bluetoothctl list`), or try \
             `droidctl --sim`"
        );
    }

    #[test]
    fn dbus_names_map_to_kinds() {
        use BleErrorKind::*;
        let k = |n: &str, m: &str| BleError::from_dbus(Some(n), m).kind;
        assert_eq!(
            k(
                "org.freedesktop.DBus.Error.FileNotFound",
                "Failed to connect to socket /run/dbus/system_bus_socket"
            ),
            NoSystemBus
        );
        assert_eq!(k("org.freedesktop.DBus.Error.NoServer", ""), NoSystemBus);
        assert_eq!(
            k("org.freedesktop.DBus.Error.ServiceUnknown", "org.bluez"),
            BluezNotRunning
        );
        assert_eq!(
            k("org.freedesktop.DBus.Error.AccessDenied", ""),
            PermissionDenied
        );
        assert_eq!(k("org.bluez.Error.NotPermitted", ""), PermissionDenied);
        assert_eq!(
            k("org.bluez.Error.NotReady", "Resource Not Ready"),
            AdapterOff
        );
        assert_eq!(
            k("org.bluez.Error.Failed", "le-connection-abort-by-local"),
            ConnectFailed
        );
        assert_eq!(
            k("org.bluez.Error.Failed", "Software caused connection abort"),
            ConnectFailed
        );
        assert_eq!(k("org.bluez.Error.Failed", "Not connected"), Disconnected);
        assert_eq!(k("org.freedesktop.DBus.Error.NoReply", ""), Timeout);
        assert_eq!(k("org.freedesktop.DBus.Error.UnknownObject", ""), NotFound);
        assert_eq!(k("com.example.Weird", "odd"), Other);
        assert!(!BleError::from_dbus(Some("org.bluez.Error.Failed"), "x").fatal());
    }

    #[test]
    fn into_link_error_keeps_fatality() {
        let l: LinkError = BleError::no_adapter().into();
        assert!(l.fatal);
        let l: LinkError = BleError::timeout("connecting", 10.0).into();
        assert!(!l.fatal);
        assert!(l.message.contains("timed out after 10 s"));
    }

    #[test]
    fn finds_dbus_names_in_debug_text() {
        assert_eq!(
            dbus_error_in(
                "DbusError(D-Bus error: le-connection-abort-by-local (org.bluez.Error.Failed))"
            ),
            Some((
                "org.bluez.Error.Failed".into(),
                "le-connection-abort-by-local".into()
            ))
        );
        assert_eq!(
            dbus_error_in("D-Bus error: Resource Not Ready (org.bluez.Error.NotReady)"),
            Some((
                "org.bluez.Error.NotReady".into(),
                "Resource Not Ready".into()
            ))
        );
        assert_eq!(
            dbus_error_in("D-Bus error: a (b) c (org.bluez.Error.Failed)"),
            Some(("org.bluez.Error.Failed".into(), "a (b) c".into()))
        );
        assert_eq!(dbus_error_in("ServiceDiscoveryTimedOut"), None);
    }

    /// `(text btleplug gives, the kind it maps to)` on one platform.
    fn check(os: Os, cases: &[(&str, BleErrorKind)]) {
        for (text, kind) in cases {
            let e = BleError::from_platform_text(os, text);
            assert_eq!(e.kind, *kind, "{os:?}: {text:?} -> {e}");
            assert!(!e.message.is_empty() && !e.message.contains('\n'), "{e}");
            use BleErrorKind::*;
            if matches!(e.kind, NoAdapter | AdapterOff | PermissionDenied) {
                assert!(e.message.contains("`droidctl --sim`"), "{os:?}: {e}");
            }
        }
    }

    #[test]
    fn linux_texts_map_as_before() {
        use BleErrorKind::*;
        check(
            Os::Linux,
            &[
                // bluez-async's Debug rendering of a wrapped D-Bus error.
                (
                    "DbusError(D-Bus error: Resource Not Ready (org.bluez.Error.NotReady))",
                    AdapterOff,
                ),
                (
                    "DbusError(D-Bus error: le-connection-abort-by-local (org.bluez.Error.Failed))",
                    ConnectFailed,
                ),
                ("No Bluetooth adapters found", NoAdapter),
                ("Service discovery timed out", Timeout),
                (
                    "Characteristic with UUID 00010002-574f-4f20-5370-6865726f2121 not found",
                    MissingCharacteristic,
                ),
                ("Permission denied", PermissionDenied),
                ("something new", Other),
            ],
        );
        let e = BleError::from_platform_text(Os::Linux, "No Bluetooth adapter available");
        assert_eq!(e, BleError::no_adapter());
        assert_eq!(
            BleError::from_platform_text(Os::Linux, "something new").message,
            "Bluetooth error: something new"
        );
    }

    #[test]
    fn macos_texts_map_to_kinds() {
        use BleErrorKind::*;
        check(
            Os::MacOs,
            &[
                // btleplug's `Error::PermissionDenied`: the terminal app was refused Bluetooth.
                ("Permission denied", PermissionDenied),
                ("No Bluetooth adapter available", NoAdapter),
                // `CBManagerState`s as they appear in messages.
                ("Bluetooth state: poweredOff", AdapterOff),
                ("CBManagerState unauthorized", PermissionDenied),
                ("Bluetooth LE is unsupported on this device", NoAdapter),
                // btleplug's own: CoreBluetooth never reported a state.
                ("Adapter failed to connect.", PermissionDenied),
                // `Error::RuntimeError` with NSError's localized description.
                (
                    "Runtime Error: The connection has failed unexpectedly.",
                    ConnectFailed,
                ),
                (
                    "Runtime Error: The connection has timed out unexpectedly.",
                    Timeout,
                ),
                (
                    "Runtime Error: The specified device has disconnected from us.",
                    Disconnected,
                ),
                ("Runtime Error: The device is not connected.", Disconnected),
                (
                    "Runtime Error: Peer removed pairing information",
                    ConnectFailed,
                ),
                ("Runtime Error: Peripheral no longer available", NotFound),
                ("Runtime Error: Unknown device.", NotFound),
                ("Channel closed", Other),
            ],
        );
        let perm = BleError::from_platform_text(Os::MacOs, "Permission denied");
        assert!(
            perm.message.contains("Privacy & Security → Bluetooth"),
            "{perm}"
        );
        let off = BleError::from_platform_text(Os::MacOs, "state: poweredOff");
        assert!(off.message.contains("System Settings → Bluetooth"), "{off}");
        assert!(!off.message.contains("bluetoothctl"), "{off}");
        let failed = BleError::from_platform_text(
            Os::MacOs,
            "Runtime Error: The connection has failed unexpectedly.",
        );
        assert!(
            failed
                .message
                .contains("(The connection has failed unexpectedly.)"),
            "{failed}"
        );
    }

    #[test]
    fn windows_texts_map_to_kinds_by_hresult() {
        use BleErrorKind::*;
        check(
            Os::Windows,
            &[
                // Scanning with the radio off.
                (
                    r#"Error { code: HRESULT(0x800710DF), message: "The device is not ready for use." }"#,
                    AdapterOff,
                ),
                // Localized messages: the HRESULT decides.
                (
                    r#"Error { code: HRESULT(0x80070005), message: "拒绝访问。" }"#,
                    PermissionDenied,
                ),
                (
                    r#"Error { code: HRESULT(0x8007048F), message: "The device is not connected." }"#,
                    Disconnected,
                ),
                (
                    r#"Error { code: HRESULT(0x80000013), message: "The object has been closed." }"#,
                    Disconnected,
                ),
                (
                    r#"Error { code: HRESULT(0x800705B4), message: "This operation returned because the timeout period expired." }"#,
                    Timeout,
                ),
                (
                    r#"Error { code: HRESULT(0x80070490), message: "Element not found." }"#,
                    NotFound,
                ),
                (
                    r#"Error { code: HRESULT(0x8000FFFF), message: "Catastrophic failure" }"#,
                    ConnectFailed,
                ),
                (
                    r#"Error { code: HRESULT(0x80004002), message: "No such interface supported" }"#,
                    NoAdapter,
                ),
                // btleplug's typed errors and its own texts.
                ("Permission denied", PermissionDenied),
                ("No Bluetooth adapter available", NoAdapter),
                ("Communication Error:", Other),
                (
                    r#"Error { code: HRESULT(0x80650003), message: "The attribute cannot be written." }"#,
                    Other,
                ),
            ],
        );
        let off = BleError::from_platform_text(
            Os::Windows,
            r#"Error { code: HRESULT(0x800710DF), message: "x" }"#,
        );
        assert!(
            off.message.contains("Settings → Bluetooth & devices"),
            "{off}"
        );
        assert_eq!(hresult_in("HRESULT(0x800710DF)"), Some(0x8007_10DF));
        assert_eq!(hresult_in("HRESULT(0xZZ)"), None);
    }

    #[test]
    fn every_platform_has_its_own_no_bluetooth_messages() {
        for os in [Os::Linux, Os::MacOs, Os::Windows] {
            for e in [
                BleError::no_adapter_on(os),
                BleError::adapter_off_on(os),
                BleError::permission_denied_on(os),
                BleError::unavailable_on(os),
            ] {
                assert!(e.fatal(), "{os:?}: {e}");
                assert!(e.message.contains("`droidctl --sim`"), "{os:?}: {e}");
                assert!(!e.message.contains('\n'), "{os:?}: {e}");
                let linux_only = ["bluetoothctl", "BlueZ", "rfkill", "usermod"];
                if os != Os::Linux {
                    assert!(
                        linux_only.iter().all(|w| !e.message.contains(w)),
                        "{os:?}: {e}"
                    );
                }
            }
        }
        assert_eq!(BleError::adapter_off(), BleError::adapter_off_on(Os::Linux));
        assert_eq!(
            BleError::device_gone_on(Os::Linux).message,
            "BlueZ no longer knows the device — scan again (is the droid awake?)"
        );
    }

    #[test]
    fn messages_are_one_line() {
        let e = BleError::new(BleErrorKind::Other, "a\nb  c");
        assert_eq!(e.message, "a b c");
    }
}
