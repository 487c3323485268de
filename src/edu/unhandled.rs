//! Promises rejected with nothing to handle them: an `async` helper called without `await`
//! that throws. Sphero Edu programs call such helpers often (`blink();` with `blink` async);
//! without this their errors vanish and the program goes on, or ends with exit 0 having done
//! nothing. Boa tells the host of each rejection with no handler, and of a handler added
//! later (ECMAScript's HostPromiseRejectionTracker); what is still unhandled at the end of a
//! turn fails the program with its line.

use boa_engine::Context;
use boa_engine::builtins::promise::{OperationType, Promise};
use boa_engine::context::HostHooks;
use boa_engine::object::JsObject;
use std::cell::RefCell;
use std::rc::Rc;

/// The most rejections kept at once (the first is what the program fails with).
const MAX_KEPT: usize = 64;

thread_local! {
    static UNHANDLED: RefCell<Vec<JsObject<Promise>>> = const { RefCell::new(Vec::new()) };
}

/// The engine's host hooks: Boa's defaults, and the rejections tracked.
pub(super) struct Tracker;

impl HostHooks for Tracker {
    fn promise_rejection_tracker(
        &self,
        promise: &JsObject<Promise>,
        operation: OperationType,
        _context: &mut Context,
    ) {
        UNHANDLED.with(|u| {
            let mut u = u.borrow_mut();
            match operation {
                OperationType::Reject if u.len() < MAX_KEPT => u.push(promise.clone()),
                OperationType::Reject => {}
                OperationType::Handle => {
                    let handled = promise.clone().upcast();
                    u.retain(|p| !JsObject::equals(&p.clone().upcast(), &handled));
                }
            }
        })
    }
}

pub(super) fn hooks() -> Rc<Tracker> {
    Rc::new(Tracker)
}

/// The promises rejected and still unhandled since the last call, oldest first.
pub(super) fn take() -> Vec<JsObject<Promise>> {
    UNHANDLED.with(|u| std::mem::take(&mut *u.borrow_mut()))
}
