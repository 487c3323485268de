//! The one way droidctl takes a `std::sync::Mutex`.
//!
//! A panic in a thread holding one of droidctl's locks cannot leave the data half-updated in
//! a way that matters more than going on (stopping the droid, answering the next client,
//! flushing a capture): so a poisoned lock is taken anyway instead of panicking in turn. One
//! helper so every module makes that choice the same way (it was copied into ten of them).

use std::sync::{Mutex, MutexGuard, PoisonError};

/// Lock `m`, poisoned or not.
pub fn lock<T: ?Sized>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

#[cfg(test)]
mod tests {
    use super::lock;
    use std::sync::Mutex;

    #[test]
    fn a_poisoned_lock_is_taken_with_its_data() {
        let m = Mutex::new(1);
        let _ = std::panic::catch_unwind(|| {
            let mut g = lock(&m);
            *g = 2;
            panic!("poison it");
        });
        assert!(m.is_poisoned());
        assert_eq!(*lock(&m), 2);
    }
}
