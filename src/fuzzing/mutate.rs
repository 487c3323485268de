//! A seeded mutator for fuzzing on stable Rust: inputs made from a seed corpus by the
//! mutations libFuzzer also uses (bit flips, interesting bytes and numbers, inserts,
//! deletions, repeats, splices between corpus entries, and the target's dictionary words).
//! No coverage feedback: what it finds comes from the corpus and the dictionary, so both
//! should hold realistic inputs. Same seed, same inputs.

use crate::rng::Rng;

/// Bytes that sit on decision points of droidctl's formats: framing (v2 8D/D8/AB, v1 FF,
/// RSRCP 7E), escapes, line ends and separators, and boundary values.
const INTERESTING: &[u8] = &[
    0x00, 0x01, 0x02, 0x7E, 0x7F, 0x80, 0x8D, 0xAB, 0xD8, 0xFE, 0xFF, b'\n', b' ', b'#', b'.',
    b':', b'=', b'"', b'[', b'0', b'9', b'-', b'e',
];

/// Numbers written as text where a harness reads text (durations, times, sizes).
const NUMBERS: &[&str] = &[
    "0",
    "1",
    "-1",
    "255",
    "256",
    "359",
    "360",
    "65535",
    "65536",
    "86400",
    "86401",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "18446744073709551616",
    "1e20",
    "1e300",
    "NaN",
    "inf",
    "-0",
    "0.0005",
    "999999999999.999",
];

/// Largest input made (bigger ones are cut).
pub const MAX_LEN: usize = 16 * 1024;

pub struct Mutator {
    rng: Rng,
    /// The corpus, then inputs made from it (a bounded pool, so mutations stack).
    pool: Vec<Vec<u8>>,
    seeds: usize,
    dictionary: &'static [&'static [u8]],
}

impl Mutator {
    pub fn new(seed: u64, corpus: &[Vec<u8>], dictionary: &'static [&'static [u8]]) -> Self {
        let mut pool: Vec<Vec<u8>> = corpus.to_vec();
        if pool.is_empty() {
            pool.push(Vec::new());
        }
        Mutator {
            rng: Rng::new(seed),
            seeds: pool.len(),
            pool,
            dictionary,
        }
    }

    fn below(&mut self, n: usize) -> usize {
        self.rng.below(n as u64) as usize
    }

    /// The next input: a pool entry with one to eight mutations (fewer more often).
    pub fn next_input(&mut self) -> Vec<u8> {
        let i = self.below(self.pool.len());
        let mut data = self.pool[i].clone();
        // One mutation half the time, two a quarter …: most inputs stay near a seed.
        let n = 1 + (self.rng.next_u64().trailing_zeros() as usize).min(7);
        for _ in 0..n {
            self.mutate(&mut data);
        }
        data.truncate(MAX_LEN);
        // Keep some of what was made, so later inputs build on it (the seeds stay).
        if self.rng.chance(0.1) {
            if self.pool.len() < self.seeds + 512 {
                self.pool.push(data.clone());
            } else {
                let j = self.seeds + self.below(512);
                self.pool[j] = data.clone();
            }
        }
        data
    }

    fn mutate(&mut self, data: &mut Vec<u8>) {
        let at = |m: &mut Self, len: usize| m.below(len + 1);
        match self.below(15) {
            0 if !data.is_empty() => {
                let i = self.below(data.len());
                data[i] ^= 1 << self.below(8);
            }
            1 if !data.is_empty() => {
                let i = self.below(data.len());
                data[i] = self.rng.byte();
            }
            2 if !data.is_empty() => {
                let i = self.below(data.len());
                data[i] = INTERESTING[self.below(INTERESTING.len())];
            }
            3 => {
                let i = at(self, data.len());
                // One mutation half the time, two a quarter …: most inputs stay near a seed.
                let n = 1 + (self.rng.next_u64().trailing_zeros() as usize).min(7);
                let bytes: Vec<u8> = (0..n).map(|_| self.rng.byte()).collect();
                data.splice(i..i, bytes);
            }
            4 if !data.is_empty() => {
                let i = self.below(data.len());
                let n = 1 + self.below((data.len() - i).min(32));
                data.drain(i..i + n);
            }
            5 if !data.is_empty() => {
                // Repeat a piece (long runs find bounds).
                let i = self.below(data.len());
                let n = 1 + self.below((data.len() - i).min(64));
                let piece = data[i..i + n].to_vec();
                let times = 1 + self.below(16);
                let at = at(self, data.len());
                for _ in 0..times {
                    data.splice(at..at, piece.iter().copied());
                }
            }
            6 => {
                // Splice in a piece of another input.
                let j = self.below(self.pool.len());
                let other = self.pool[j].clone();
                if !other.is_empty() {
                    let i = self.below(other.len());
                    let n = 1 + self.below(other.len() - i);
                    let at = at(self, data.len());
                    data.splice(at..at, other[i..i + n].iter().copied());
                }
            }
            7 | 8 if !self.dictionary.is_empty() => {
                let word = self.dictionary[self.below(self.dictionary.len())];
                let i = at(self, data.len());
                if self.rng.chance(0.5) || data.len() < i + word.len() {
                    data.splice(i..i, word.iter().copied());
                } else {
                    data[i..i + word.len()].copy_from_slice(word);
                }
            }
            9 => {
                // A number as text, replacing the digits there or inserted.
                let word = NUMBERS[self.below(NUMBERS.len())].as_bytes();
                let i = at(self, data.len());
                let end = data[i..]
                    .iter()
                    .position(|b| !b.is_ascii_digit() && *b != b'.')
                    .map_or(data.len(), |p| i + p);
                data.splice(i..end, word.iter().copied());
            }
            10 if data.len() >= 2 => {
                // A binary integer at a random place, little- or big-endian.
                let width = [1usize, 2, 4, 8][self.below(4)].min(data.len());
                let i = self.below(data.len() - width + 1);
                let v: u64 = match self.below(4) {
                    0 => 0,
                    1 => u64::MAX,
                    2 => 1 << self.below(64),
                    _ => self.rng.next_u64(),
                };
                let bytes = if self.rng.chance(0.5) {
                    v.to_le_bytes()
                } else {
                    v.to_be_bytes()
                };
                data[i..i + width].copy_from_slice(&bytes[..width]);
            }
            11 if data.len() > 1 => {
                let n = self.below(data.len());
                data.truncate(n);
            }
            12 | 13 if data.contains(&b'\n') => {
                // Text formats: a whole line deleted or repeated (keeps the rest readable).
                let lines = line_starts(data);
                let i = self.below(lines.len());
                let (a, b) = (lines[i], lines.get(i + 1).copied().unwrap_or(data.len()));
                if self.rng.chance(0.5) {
                    data.drain(a..b);
                } else {
                    let line = data[a..b].to_vec();
                    let at = lines[self.below(lines.len())];
                    data.splice(at..at, line);
                }
            }
            14 => {
                // Text formats: the word after a separator (`=`, a space) becomes a number
                // or a dictionary word.
                let seps: Vec<usize> = (0..data.len())
                    .filter(|&i| matches!(data[i], b'=' | b' '))
                    .collect();
                if seps.is_empty() {
                    return;
                }
                let start = seps[self.below(seps.len())] + 1;
                let start = start + data[start..].iter().take_while(|b| **b == b' ').count();
                let end = start
                    + data[start..]
                        .iter()
                        .position(|b| matches!(b, b' ' | b'\n' | b',' | b']'))
                        .unwrap_or(data.len() - start);
                let word: &[u8] = if self.rng.chance(0.5) || self.dictionary.is_empty() {
                    NUMBERS[self.below(NUMBERS.len())].as_bytes()
                } else {
                    self.dictionary[self.below(self.dictionary.len())]
                };
                data.splice(start..end, word.iter().copied());
            }
            _ => data.push(self.rng.byte()),
        }
    }
}

/// Where each line of `data` starts.
fn line_starts(data: &[u8]) -> Vec<usize> {
    std::iter::once(0)
        .chain(
            data.iter()
                .enumerate()
                .filter(|(i, b)| **b == b'\n' && i + 1 < data.len())
                .map(|(i, _)| i + 1),
        )
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_inputs_and_bounded() {
        let corpus = vec![b"wait 1s\n".to_vec(), vec![0x8D, 0x0A, 0xD8]];
        let mut a = Mutator::new(7, &corpus, &[b"drive"]);
        let mut b = Mutator::new(7, &corpus, &[b"drive"]);
        for _ in 0..2000 {
            let x = a.next_input();
            assert_eq!(x, b.next_input());
            assert!(x.len() <= MAX_LEN);
        }
    }
}
