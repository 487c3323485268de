//! Packets off the wire and onto it, with what MQTT 3.1.1 says a server must refuse checked
//! before rumqttc's codec reads them (sans-IO but for [`read`] and [`write`]).
//!
//! The codec is a client's: it takes any fixed-header flags, an MQTT 5 CONNECT as if it were
//! 3.1.1, and U+0000 in topics. A server must close the connection for reserved flags that
//! are wrong (3.1.1, 2.2.2-2: SUBSCRIBE, UNSUBSCRIBE and PUBREL carry 0b0010, the others
//! 0), answer a protocol level it does not speak with CONNACK return code 1 (3.1.2-2: MQTT
//! 3.1's `MQIsdp` level 3, MQTT 5's level 5), and close for U+0000 in a topic name or
//! filter (1.5.3-2).

use super::limits::{MAX_CLIENT_ID, MAX_CONNECT, MAX_PACKET, MAX_TOPIC, WRITE_TIMEOUT};
use bytes::BytesMut;
use rumqttc::mqttbytes::v4::Packet;
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};

/// Why a connection is closed (or refused), as the log says it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum WireError {
    #[error("malformed packet: {0}")]
    Malformed(String),
    #[error("a packet of {0} bytes, over the limit of {1}")]
    TooLarge(usize, usize),
    #[error("wrong reserved flags {flags:#06b} on a packet of type {kind}")]
    ReservedFlags { kind: u8, flags: u8 },
    #[error("protocol {name:?} level {level}: only MQTT 3.1.1 (level 4) is spoken")]
    Protocol { name: String, level: u8 },
    #[error("U+0000 in a topic name, filter or client id")]
    Nul,
    #[error("a topic name over {MAX_TOPIC} bytes or empty")]
    Topic,
    #[error("a wildcard (+, #) in a topic name")]
    Wildcard,
    #[error("a client id over {MAX_CLIENT_ID} bytes")]
    ClientId,
    #[error("{0}")]
    Io(String),
    #[error("a write stalled for {} s: the client does not read", WRITE_TIMEOUT.as_secs())]
    WriteTimeout,
}

/// The packet types' numbers (the fixed header's high nibble).
const CONNECT: u8 = 1;
const PUBLISH: u8 = 3;
const PUBREL: u8 = 6;
const SUBSCRIBE: u8 = 8;
const UNSUBSCRIBE: u8 = 10;

/// The fixed header's flags a server must see for packet type `kind` (`None`: PUBLISH,
/// whose flags are its own).
fn reserved_flags(kind: u8) -> Option<u8> {
    match kind {
        PUBLISH => None,
        PUBREL | SUBSCRIBE | UNSUBSCRIBE => Some(0b0010),
        _ => Some(0),
    }
}

/// The remaining length a fixed header at the start of `buf` declares, and the header's
/// length; `Ok(None)`: more bytes are needed.
fn remaining_length(buf: &[u8]) -> Result<Option<(usize, usize)>, WireError> {
    let mut len = 0usize;
    for (i, b) in buf.iter().skip(1).take(4).enumerate() {
        len |= usize::from(b & 0x7F) << (7 * i);
        if b & 0x80 == 0 {
            return Ok(Some((len, i + 2)));
        }
    }
    if buf.len() >= 5 {
        return Err(WireError::Malformed(
            "a remaining length over 4 bytes".into(),
        ));
    }
    Ok(None)
}

/// One whole packet at the front of `buf`, taken off it, checked and decoded; `Ok(None)`: more
/// bytes are needed. `first`: this is the connection's first packet (it must be CONNECT, and
/// is held to [`MAX_CONNECT`]). Nothing is read past a header that breaks a rule.
pub fn frame(buf: &mut BytesMut, first: bool) -> Result<Option<Packet>, WireError> {
    let Some(&byte1) = buf.first() else {
        return Ok(None);
    };
    let (kind, flags) = (byte1 >> 4, byte1 & 0x0F);
    if first && kind != CONNECT {
        return Err(WireError::Malformed(
            "the first packet is not CONNECT".into(),
        ));
    }
    if let Some(want) = reserved_flags(kind)
        && flags != want
    {
        return Err(WireError::ReservedFlags { kind, flags });
    }
    let Some((len, header)) = remaining_length(buf)? else {
        return Ok(None);
    };
    let max = if kind == CONNECT {
        MAX_CONNECT
    } else {
        MAX_PACKET
    };
    if len > max {
        return Err(WireError::TooLarge(len, max));
    }
    if buf.len() < header + len {
        return Ok(None);
    }
    if kind == CONNECT {
        check_protocol(&buf[header..header + len])?;
    }
    let p = Packet::read(buf, max).map_err(|e| WireError::Malformed(format!("{e:?}")))?;
    check_strings(&p)?;
    Ok(Some(p))
}

/// A CONNECT's protocol name and level (its variable header's start): only `MQTT` level 4.
fn check_protocol(body: &[u8]) -> Result<(), WireError> {
    let short = || WireError::Malformed("a CONNECT too short for its protocol name".into());
    let n = usize::from(u16::from_be_bytes([
        *body.first().ok_or_else(short)?,
        *body.get(1).ok_or_else(short)?,
    ]));
    let name = body.get(2..2 + n).ok_or_else(short)?;
    let level = *body.get(2 + n).ok_or_else(short)?;
    if name != b"MQTT" || level != 4 {
        return Err(WireError::Protocol {
            name: String::from_utf8_lossy(name).into_owned(),
            level,
        });
    }
    let connect_flags = *body.get(3 + n).ok_or_else(short)?;
    if connect_flags & 1 != 0 {
        return Err(WireError::Malformed(
            "CONNECT's reserved flag is set".into(),
        ));
    }
    Ok(())
}

/// Topic names, filters and client ids: no U+0000, within their lengths.
fn check_strings(p: &Packet) -> Result<(), WireError> {
    let nul = |s: &str| s.contains('\0');
    match p {
        Packet::Connect(c) => {
            if nul(&c.client_id) || c.last_will.as_ref().is_some_and(|w| nul(&w.topic)) {
                return Err(WireError::Nul);
            }
            if c.client_id.len() > MAX_CLIENT_ID {
                return Err(WireError::ClientId);
            }
            if let Some(w) = &c.last_will
                && (w.topic.is_empty() || w.topic.len() > MAX_TOPIC)
            {
                return Err(WireError::Topic);
            }
        }
        Packet::Publish(p) => {
            if nul(&p.topic) {
                return Err(WireError::Nul);
            }
            if p.topic.is_empty() || p.topic.len() > MAX_TOPIC {
                return Err(WireError::Topic);
            }
        }
        Packet::Subscribe(s) if s.filters.iter().any(|f| nul(&f.path)) => {
            return Err(WireError::Nul);
        }
        Packet::Unsubscribe(u) if u.topics.iter().any(|t| nul(t)) => {
            return Err(WireError::Nul);
        }
        _ => {}
    }
    Ok(())
}

/// Read one packet, reading more bytes as needed. `Ok(None)`: the peer closed.
pub async fn read<S: AsyncRead + Unpin>(
    s: &mut S,
    buf: &mut BytesMut,
    first: bool,
) -> Result<Option<Packet>, WireError> {
    loop {
        if let Some(p) = frame(buf, first)? {
            return Ok(Some(p));
        }
        buf.reserve(4096);
        if s.read_buf(buf)
            .await
            .map_err(|e| WireError::Io(e.to_string()))?
            == 0
        {
            return Ok(None);
        }
    }
}

/// Write one packet, within [`WRITE_TIMEOUT`].
pub async fn write<S: AsyncWrite + Unpin>(s: &mut S, p: &Packet) -> Result<(), WireError> {
    let mut b = BytesMut::new();
    p.write(&mut b, usize::MAX)
        .map_err(|e| WireError::Malformed(format!("cannot encode: {e:?}")))?;
    match tokio::time::timeout(WRITE_TIMEOUT, s.write_all(&b)).await {
        Ok(r) => r.map_err(|e| WireError::Io(e.to_string())),
        Err(_) => Err(WireError::WriteTimeout),
    }
}

/// Encoded packets for tests and the fuzz harness (as a client writes them).
pub fn encode(p: &Packet) -> Vec<u8> {
    let mut b = BytesMut::new();
    // Encoding a packet made here fails only beyond MQTT's 256 MiB: a test's own mistake.
    let _ = p.write(&mut b, usize::MAX);
    b.to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rumqttc::mqttbytes::QoS;
    use rumqttc::mqttbytes::v4::{Connect, Publish, Subscribe};

    fn framed(bytes: &[u8]) -> Result<Option<Packet>, WireError> {
        frame(&mut BytesMut::from(bytes), false)
    }

    #[test]
    fn subscribe_unsubscribe_and_pubrel_need_their_reserved_flags() {
        let mut sub = encode(&Packet::Subscribe(Subscribe::new("a/#", QoS::AtMostOnce)));
        assert!(matches!(framed(&sub), Ok(Some(Packet::Subscribe(_)))));
        sub[0] = 0x80;
        assert_eq!(
            framed(&sub),
            Err(WireError::ReservedFlags { kind: 8, flags: 0 })
        );
        // PINGREQ with a flag set: refused at the first byte, before any length.
        assert!(matches!(
            framed(&[0xC1]),
            Err(WireError::ReservedFlags { .. })
        ));
    }

    #[test]
    fn only_mqtt_3_1_1_connects() {
        let c = encode(&Packet::Connect(Connect::new("c")));
        assert!(matches!(
            frame(&mut BytesMut::from(&c[..]), true),
            Ok(Some(Packet::Connect(_)))
        ));
        let mut v5 = c.clone();
        // Fixed header 2 bytes, then the name's length (2) and "MQTT" (4): the level.
        v5[8] = 5;
        assert!(matches!(
            frame(&mut BytesMut::from(&v5[..]), true),
            Err(WireError::Protocol { level: 5, .. })
        ));
        // MQTT 3.1: "MQIsdp", level 3.
        let mut v3 = vec![0x10, 0];
        v3.extend_from_slice(&[0, 6]);
        v3.extend_from_slice(b"MQIsdp");
        v3.extend_from_slice(&[3, 2, 0, 60, 0, 1, b'c']);
        v3[1] = (v3.len() - 2) as u8;
        assert!(matches!(
            frame(&mut BytesMut::from(&v3[..]), true),
            Err(WireError::Protocol { level: 3, .. })
        ));
    }

    #[test]
    fn nul_in_a_topic_and_oversize_packets_are_refused_unread() {
        let p = encode(&Packet::Publish(Publish::new(
            "a/\0/b",
            QoS::AtMostOnce,
            "x",
        )));
        assert_eq!(framed(&p), Err(WireError::Nul));
        // A 1.7 MB SUBSCRIBE is refused from its header alone.
        let mut big = vec![0x82];
        let mut n = 1_700_000usize;
        while n > 0x7F {
            big.push((n as u8 & 0x7F) | 0x80);
            n >>= 7;
        }
        big.push(n as u8);
        assert_eq!(
            framed(&big),
            Err(WireError::TooLarge(1_700_000, MAX_PACKET))
        );
        // The first packet must be CONNECT, seen at its first byte.
        assert!(frame(&mut BytesMut::from(&[0x30u8][..]), true).is_err());
    }
}
