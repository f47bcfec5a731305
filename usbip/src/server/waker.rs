//! The handle a device's producer uses to tell the server that bulk-in data may be ready.

use std::sync::{Arc, Condvar, Mutex, PoisonError};

use super::sync::lock;

/// Wakes the server to ask the device again for queued bulk-in requests. Cheap to clone; valid for the
/// server's whole life, across host sessions. Wakes do not queue up: several before the server looks count
/// as one.
#[derive(Debug, Clone, Default)]
pub struct Waker {
    inner: Arc<WakeFlag>,
}

#[derive(Debug, Default)]
struct WakeFlag {
    woken: Mutex<bool>,
    condvar: Condvar,
}

impl Waker {
    /// Asks the server to poll the device's queued bulk-in requests.
    pub fn wake(&self) {
        *lock(&self.inner.woken) = true;
        self.inner.condvar.notify_all();
    }

    /// Blocks until woken, then clears the flag.
    pub(crate) fn wait(&self) {
        let mut woken = lock(&self.inner.woken);
        while !*woken {
            woken = self
                .inner
                .condvar
                .wait(woken)
                .unwrap_or_else(PoisonError::into_inner);
        }
        *woken = false;
    }
}
