//! The btsnoop reader (phone and `btmon` logs): any bytes in any pieces read to the same
//! header, records and damage as the whole file at once; every byte is accounted for (each
//! record starts where the last ended); after damage nothing more is read; reading moves at
//! most the input's size within its buffer (linear, however it is fed). The whole log then
//! loads for replay (`droidctl replay LOG`) as a capture or one error, and replays.
//!
//! Input layout: the first byte's low nibble counts chunk sizes (as the decoder target), its
//! high nibble picks `--handle` and the replay's model; the rest is the log.

use super::{Target, feeds, split};
use crate::capture::btsnoop::{self, Item, Reader};
use crate::capture::hci::capture_from_btsnoop;

pub const TARGET: Target = Target {
    name: "btsnoop",
    run: run_input,
    dictionary: &[
        b"btsnoop\0",
        &[0, 0, 0, 1],
        &[0, 0, 0x03, 0xE9],
        &[0, 0, 0x03, 0xEA],
        &[0, 0, 0x07, 0xD1],
        &[0x00, 0xDC, 0xDD, 0xB3, 0x0F, 0x2F, 0x80, 0x00],
        &[0x7F, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF],
        &[0x00, 0x10, 0x00, 0x00],
    ],
};

/// What a reader made of a log: items (damage by kind and offset: its text may show fewer
/// bytes when the log came in small pieces), then what `finish` said.
#[derive(Debug, PartialEq, Eq)]
enum Seen {
    Header(btsnoop::Header),
    Record(btsnoop::Record),
    Damage(btsnoop::ErrorKind, u64),
}

fn read(pieces: &[&[u8]], total: usize) -> Vec<Seen> {
    let mut r = Reader::new();
    let mut seen = Vec::new();
    let mut at = 0u64;
    let mut records = 0u64;
    let mut failed = false;
    for p in pieces {
        r.feed(p);
        while let Some(item) = r.next_item() {
            assert!(!failed, "an item after damage");
            match item {
                Ok(Item::Header(h)) => {
                    assert_eq!(at, 0);
                    at = btsnoop::HEADER_LEN as u64;
                    seen.push(Seen::Header(h));
                }
                Ok(Item::Record(rec)) => {
                    assert_eq!(rec.offset, at, "records follow each other");
                    assert!(rec.data.len() as u32 <= btsnoop::MAX_RECORD);
                    at += (btsnoop::RECORD_HEADER_LEN + rec.data.len()) as u64;
                    records += 1;
                    seen.push(Seen::Record(rec));
                }
                Err(e) => {
                    assert!(!e.to_string().is_empty());
                    failed = true;
                    seen.push(Seen::Damage(e.kind, e.offset));
                }
            }
            assert_eq!(r.records(), records);
            assert!(r.offset() <= total as u64);
        }
    }
    if let Some(e) = r.finish() {
        assert!(!failed, "damage reported twice");
        assert_eq!(e.kind, btsnoop::ErrorKind::Truncated);
        seen.push(Seen::Damage(e.kind, e.offset));
    } else if !failed {
        assert_eq!(
            at, total as u64,
            "a log read without damage is read to its end"
        );
    }
    // More input after the end changes nothing once it failed.
    if failed {
        r.feed(&[0u8; 64]);
        assert!(r.next_item().is_none());
    }
    assert!(
        r.bytes_moved() <= total as u64,
        "moved {} bytes reading {total}",
        r.bytes_moved()
    );
    seen
}

pub fn run_input(data: &[u8]) {
    let Some((opts, sizes, log)) = split(data) else {
        return;
    };
    let whole = read(&[log], log.len());
    let cut = read(&feeds(sizes, log), log.len());
    assert_eq!(whole, cut, "the same log read in pieces");

    // Replay's loader, with or without a handle given.
    let handles: &[u16] = match opts & 3 {
        0 | 1 => &[],
        2 => &[0x0012],
        _ => &[0x0010, 0x0012, 0x0015],
    };
    match capture_from_btsnoop(log, handles) {
        Ok(c) => {
            assert!(!c.events.is_empty(), "a capture holds the droid's traffic");
            assert!(c.events.windows(2).all(|w| w[0].at <= w[1].at));
            super::capture::check_replay(&c, opts >> 2, 100);
        }
        Err(e) => assert!(!e.is_empty()),
    }
}
