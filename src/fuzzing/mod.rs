//! Fuzz harnesses: one plain function per place where bytes from outside enter droidctl, each
//! asserting what must hold for any input (not only "no panic": the stream invariants, that
//! every request is answered or refused, that errors are reported, that a droid is stopped).
//!
//! Two engines run the same functions: the libFuzzer binaries in `fuzz/fuzz_targets/` (one
//! line each, `cargo +nightly fuzz run NAME`) and, on stable Rust, [`runner`] with the
//! seeded [`mutate::Mutator`]: `tests/it/fuzz_smoke.rs` runs every harness over its seed corpus
//! in `fuzz/corpus/NAME/` plus a few thousand generated inputs on each `cargo test`, and an
//! ignored test runs one for as long as it is asked to. README's "Reliability" section lists
//! the targets and what running them found.
//!
//! This module sits above everything (it drives the CLI's readers, the relay server and the
//! virtual BlueZ) and nothing uses it but the fuzz binaries and tests.

pub mod app_input;
#[cfg(target_os = "linux")]
pub mod bluez;
pub mod bridge;
pub mod bridge_mqtt;
pub mod broker;
pub mod btsnoop;
pub mod capture;
pub mod config;
pub mod decoder;
pub mod edu;
pub mod edu_wire;
pub mod fleet_capture;
pub mod hci;
pub mod mutate;
pub mod packet_file;
pub mod plot;
pub mod relay_codec;
pub mod relay_server;
pub mod ros;
pub mod runner;
pub mod script;
pub mod session_core;

/// One fuzz target: its name (the libFuzzer binary and the corpus directory), the harness, and
/// words its inputs are made of (the stable mutator splices them in).
pub struct Target {
    pub name: &'static str,
    pub run: fn(&[u8]),
    pub dictionary: &'static [&'static [u8]],
}

/// Every target, in the order README lists them.
pub fn targets() -> Vec<&'static Target> {
    let v: Vec<&'static Target> = vec![
        &decoder::TARGET,
        &relay_codec::TARGET,
        &btsnoop::TARGET,
        &hci::TARGET,
        &capture::TARGET,
        &fleet_capture::TARGET,
        &plot::TARGET,
        &script::TARGET,
        &config::TARGET,
        &packet_file::TARGET,
        &relay_server::TARGET,
        &bridge::TARGET,
        &bridge_mqtt::TARGET,
        &ros::TARGET,
        &broker::TARGET,
        &app_input::TARGET,
        &edu::TARGET,
        &edu_wire::TARGET,
        &session_core::TARGET,
    ];
    #[cfg(target_os = "linux")]
    let v = [v, vec![&bluez::TARGET]].concat();
    v
}

/// The target called `name`.
pub fn target(name: &str) -> Option<&'static Target> {
    targets().into_iter().find(|t| t.name == name)
}

/// The common input layout of the stream targets: the first byte's low nibble says how many
/// of the following bytes are chunk sizes; its high nibble is left to the harness (options);
/// the rest is the stream. `None` for an empty input.
pub fn split(data: &[u8]) -> Option<(u8, &[u8], &[u8])> {
    let (&head, rest) = data.split_first()?;
    let n = ((head & 0x0F) as usize).min(rest.len());
    let (sizes, stream) = rest.split_at(n);
    Some((head >> 4, sizes, stream))
}

/// The stream cut as the sizes say (cycled; none: one feed). A zero size is an empty feed,
/// followed by at least one byte so every feed loop makes progress.
pub fn feeds<'a>(sizes: &[u8], stream: &'a [u8]) -> Vec<&'a [u8]> {
    let mut out = Vec::new();
    let (mut pos, mut i) = (0, 0);
    while pos < stream.len() {
        let size = if sizes.is_empty() {
            stream.len()
        } else {
            sizes[i % sizes.len()] as usize
        };
        i += 1;
        if size == 0 {
            out.push(&stream[pos..pos]);
        }
        let end = (pos + size.max(1)).min(stream.len());
        out.push(&stream[pos..end]);
        pos = end;
    }
    out
}

/// Bytes as a harness reads them: takes what it needs from the front, zeros when it runs out
/// (so every input means something, and a shorter one means less).
pub struct Bytes<'a> {
    data: &'a [u8],
}

impl<'a> Bytes<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Bytes { data }
    }

    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    pub fn u8(&mut self) -> u8 {
        match self.data.split_first() {
            Some((&b, rest)) => {
                self.data = rest;
                b
            }
            None => 0,
        }
    }

    pub fn u16(&mut self) -> u16 {
        u16::from_le_bytes([self.u8(), self.u8()])
    }

    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }

    pub fn u64(&mut self) -> u64 {
        (self.u32() as u64) | ((self.u32() as u64) << 32)
    }

    /// Up to `n` bytes (fewer at the end).
    pub fn take(&mut self, n: usize) -> &'a [u8] {
        let n = n.min(self.data.len());
        let (a, b) = self.data.split_at(n);
        self.data = b;
        a
    }

    /// A length-prefixed piece: one byte of length, then that many bytes.
    pub fn piece(&mut self) -> &'a [u8] {
        let n = self.u8() as usize;
        self.take(n)
    }

    pub fn rest(&mut self) -> &'a [u8] {
        self.take(self.data.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feeds_cover_the_stream_in_order() {
        let s = b"abcdefg";
        let f = feeds(&[2, 0, 3], s);
        assert_eq!(f.concat(), s);
        assert_eq!(f, [&b"ab"[..], b"", b"c", b"def", b"g"]);
        assert_eq!(feeds(&[], s), [&s[..]]);
    }

    #[test]
    fn names_are_unique() {
        let mut names: Vec<&str> = targets().iter().map(|t| t.name).collect();
        names.sort();
        let n = names.len();
        names.dedup();
        assert_eq!(names.len(), n);
    }
}
