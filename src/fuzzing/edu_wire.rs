//! The pipe from a Sphero Edu program's engine child (src/edu/wire.rs, src/edu/host.rs): the
//! child runs whatever program it was given and may die mid-frame or be something else
//! altogether, so any bytes droidctl reads from it are frames, an error or the end, never a
//! panic and never more allocated than the frame bound; every reply decoded has its calls
//! played through droidctl's own API driver (effects, or a refusal naming the call).
//!
//! Input layout: the whole input is the child's stdout.

use super::Target;
use crate::edu::host::Calls;
use crate::edu::wire::{self, FromChild};
use crate::model::Model;

pub const TARGET: Target = Target {
    name: "edu_wire",
    run: run_input,
    dictionary: &[
        b"{\"Ready\":{\"version\":1}}",
        b"{\"Done\":{\"calls\":[",
        b"{\"line\":3,\"name\":\"roll\",\"args\":[{\"Num\":0},{\"Num\":4636737291354636288}],\"promise\":1}",
        b"{\"Text\":\"hi\"}",
        b"\"status\":\"Running\",\"listening\":[\"onCollision\"]}}",
        b"\"status\":{\"Failed\":{\"line\":2,\"message\":\"x\"}}",
        b"{\"Checked\":null}",
        b"registerMatrixAnimation",
        b"setMainLed",
        b"delay",
        b"spin",
        b"\xff\xff\xff\xff",
    ],
};

/// Read frames from `data` as droidctl reads the child's stdout, playing each reply's calls.
pub fn run_input(data: &[u8]) {
    let mut input = data;
    let mut calls = Calls::new(Model::Bolt);
    // Each frame takes at least its 4-byte length: the loop ends with the input.
    loop {
        match wire::read::<FromChild>(&mut input, wire::MAX_FROM_CHILD) {
            Ok(FromChild::Done(reply)) => {
                let waiting: Vec<u64> = reply.calls.iter().filter_map(|c| c.promise).collect();
                match calls.play(reply.calls) {
                    Ok(ops) => assert!(ops.iter().all(|o| o.text.len() <= 1004), "bounded text"),
                    Err(f) => assert!(!f.message.is_empty(), "a refusal says why"),
                }
                calls.fired(&waiting);
            }
            Ok(_) => {}
            Err(_) => break,
        }
    }
}
