//! Why Bluetooth did not work, as a kind the code can act on and one line a person can act on.
//!
//! Most machines that run droidctl without a droid have no Bluetooth at all (containers, CI,
//! servers): each way of "no Bluetooth" gets its own message saying what is missing, what to do,
//! and that `--sim` works without a radio.

use crate::link::LinkError;
use std::fmt;

/// What went wrong, coarse enough to decide between "give up" and "retry".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BleErrorKind {
    /// No D-Bus system bus to reach BlueZ through (containers, minimal systems).
    NoSystemBus,
    /// The system bus is there but BlueZ (`bluetoothd`) is not.
    BluezNotRunning,
    /// BlueZ runs but there is no adapter.
    NoAdapter,
    /// The adapter is powered off or blocked by rfkill.
    AdapterOff,
    /// BlueZ refused us (policy, group membership).
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

    pub fn no_adapter() -> Self {
        BleError::new(
            BleErrorKind::NoAdapter,
            "no Bluetooth adapter found — plug one in (check `bluetoothctl list`), or try \
             `droidctl --sim`",
        )
    }

    pub fn adapter_off() -> Self {
        BleError::new(
            BleErrorKind::AdapterOff,
            "the Bluetooth adapter is off — run `bluetoothctl power on` (and `rfkill unblock \
             bluetooth` if it is blocked), or try `droidctl --sim`",
        )
    }

    pub fn permission_denied() -> Self {
        BleError::new(
            BleErrorKind::PermissionDenied,
            "permission denied by BlueZ — add yourself to the `bluetooth` group (`sudo usermod \
             -aG bluetooth $USER`, then log in again), or try `droidctl --sim`",
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
                BleError::permission_denied()
            }
            "NotPermitted" | "NotAuthorized" if bluez => BleError::permission_denied(),
            "NotReady" if bluez => BleError::adapter_off(),
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
}

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
    fn messages_are_one_line() {
        let e = BleError::new(BleErrorKind::Other, "a\nb  c");
        assert_eq!(e.message, "a b c");
    }
}
