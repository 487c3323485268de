//! Which addresses only this machine reaches: the one loopback test behind the warnings of
//! `serve --listen`, `bridge --listen` and the bridge's `--mqtt URL` (issue 37 point 15).

use std::net::{IpAddr, SocketAddr};

/// Whether `ip` is a loopback address: `127.0.0.0/8`, `::1`, or an IPv4 loopback address
/// written as IPv6 (`::ffff:127.0.0.1`). The standard library's `IpAddr::is_loopback` says
/// no to the last, which an IPv6 socket bound there still only takes from this machine, so a
/// warning for it would be a false alarm.
pub fn is_loopback(ip: IpAddr) -> bool {
    ip.to_canonical().is_loopback()
}

/// [`is_loopback`] of a socket address's IP.
pub fn is_loopback_addr(addr: &SocketAddr) -> bool {
    is_loopback(addr.ip())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ip(s: &str) -> IpAddr {
        s.parse().unwrap_or_else(|e| panic!("{s}: {e}"))
    }

    #[test]
    fn v4_mapped_loopback_is_loopback_and_nothing_else_is() {
        for s in [
            "127.0.0.1",
            "127.5.5.5",
            "::1",
            "::ffff:127.0.0.1",
            "::ffff:127.9.8.7",
        ] {
            assert!(is_loopback(ip(s)), "{s}");
        }
        for s in [
            "0.0.0.0",
            "::",
            "::ffff:10.0.0.1",
            "::ffff:0.0.0.0",
            "10.0.0.1",
            "192.168.1.10",
            "fe80::1",
            // IPv4-compatible (deprecated) is not the mapped form: not loopback.
            "::127.0.0.1",
        ] {
            assert!(!is_loopback(ip(s)), "{s}");
        }
        let mapped: SocketAddr = "[::ffff:127.0.0.1]:1883".parse().unwrap();
        assert!(is_loopback_addr(&mapped));
        let any: SocketAddr = "[::]:1883".parse().unwrap();
        assert!(!is_loopback_addr(&any));
    }
}
