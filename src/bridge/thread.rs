//! A tokio runtime on an OS thread of its own (issue 37 point 1): what reads the network —
//! the embedded broker, the bridge's MQTT connections — runs there, so however busy or
//! blocked it gets, it cannot hold up the runtime that runs the droids' sessions, their
//! command timeouts, heartbeats and pacing.
//!
//! Tasks are spawned on its [`RuntimeThread::handle`]; channels, watches and locks connect
//! them to the other runtime as they would within one. Dropping it ends the runtime and every
//! task on it.

use std::thread::JoinHandle;
use tokio::runtime::Handle;
use tokio::sync::oneshot;

/// A current-thread runtime (IO and time enabled) running on its own thread until dropped.
pub struct RuntimeThread {
    handle: Handle,
    stop: Option<oneshot::Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl RuntimeThread {
    /// Start one; `name` names its thread (seen in `top -H`, debuggers and panics).
    pub fn start(name: &str) -> std::io::Result<RuntimeThread> {
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()?;
        let handle = rt.handle().clone();
        let (stop, stopped) = oneshot::channel::<()>();
        let thread = std::thread::Builder::new()
            .name(name.to_string())
            .spawn(move || {
                rt.block_on(async {
                    let _ = stopped.await;
                });
                // Whatever still runs (a client's connection) ends here, without waiting.
                rt.shutdown_background();
            })?;
        Ok(RuntimeThread {
            handle,
            stop: Some(stop),
            thread: Some(thread),
        })
    }

    /// Where to spawn its tasks.
    pub fn handle(&self) -> &Handle {
        &self.handle
    }
}

impl Drop for RuntimeThread {
    fn drop(&mut self) {
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
        if let Some(t) = self.thread.take() {
            // Its runtime shuts down in the background: joining waits for no task.
            let _ = t.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    /// The one test here that needs a real thread blocked: a task that blocks its runtime's
    /// thread for 400 ms (as a lock held across work that grows with input did, issue 37
    /// point 1) does not hold up a 50 ms timer on another runtime.
    #[test]
    fn a_blocked_runtime_thread_does_not_delay_another_runtimes_timers() {
        let net = RuntimeThread::start("droidctl-test-net").unwrap();
        let (blocked_tx, blocked) = std::sync::mpsc::channel();
        net.handle().spawn(async move {
            let _ = blocked_tx.send(());
            std::thread::sleep(Duration::from_millis(400));
        });
        blocked.recv().unwrap();
        let main = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .unwrap();
        let late = main.block_on(async {
            let t0 = tokio::time::Instant::now();
            tokio::time::sleep(Duration::from_millis(50)).await;
            t0.elapsed()
        });
        assert!(late < Duration::from_millis(300), "{late:?}");
        drop(net);
    }
}
