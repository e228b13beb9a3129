//! The model queue: instructions wait here, first come first served, for one of a fixed
//! number of worker threads (one for a local model, which answers one request at a
//! time). Each waiting job hears its position whenever it changes, so the page can show
//! it. Jobs run on plain threads (the backends are synchronous); a job whose requester
//! has gone is dropped unrun, and a job that panics loses only itself. Shutting the queue
//! down ([`ModelQueue::shutdown`], or dropping it) waits for the running jobs: a process
//! that exits while llama.cpp computes on another thread dies with SIGSEGV in its
//! kernels (seen under gdb in the server's API test, whose requester had timed out).

use std::collections::VecDeque;
use std::panic::AssertUnwindSafe;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;

/// A unit of work for a worker.
pub type Job = Box<dyn FnOnce() + Send + 'static>;

/// Told the job's position: `Some(k)` while waiting (1 = next), `None` when a worker
/// takes it up.
pub type PositionFn = Box<dyn Fn(Option<usize>) + Send + 'static>;

/// Asked before the job runs: `false` when nobody waits for its answer any more.
pub type WantedFn = Box<dyn Fn() -> bool + Send + 'static>;

struct Entry {
    job: Job,
    position: PositionFn,
    wanted: WantedFn,
}

#[derive(Default)]
struct State {
    waiting: VecDeque<Entry>,
    running: usize,
    closed: bool,
    served: u64,
    dropped: u64,
}

struct Inner {
    state: Mutex<State>,
    ready: Condvar,
    max_waiting: usize,
}

impl Inner {
    fn lock(&self) -> MutexGuard<'_, State> {
        // A job never runs under the lock, so a poisoned lock holds consistent data.
        self.state
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }
}

/// Why a job was not queued.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum QueueError {
    /// The queue is full.
    #[error("{waiting} instruction(s) are already waiting for the model; try again shortly")]
    Full {
        /// How many were waiting.
        waiting: usize,
    },
    /// The queue has been shut down (the server is stopping).
    #[error("the server is shutting down and takes no more instructions")]
    Closed,
}

/// How busy the queue is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct QueueStats {
    /// Jobs waiting.
    pub waiting: usize,
    /// Jobs being worked on.
    pub running: usize,
    /// Worker threads.
    pub workers: usize,
    /// Jobs run so far.
    pub served: u64,
    /// Jobs dropped unrun because their requester had gone.
    pub dropped: u64,
}

/// A first-come-first-served queue in front of `workers` threads. Dropping it shuts it
/// down ([`ModelQueue::shutdown`]).
pub struct ModelQueue {
    inner: Arc<Inner>,
    workers: usize,
    threads: Mutex<Vec<JoinHandle<()>>>,
}

impl std::fmt::Debug for ModelQueue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ModelQueue")
            .field("stats", &self.stats())
            .finish()
    }
}

impl ModelQueue {
    /// A queue with `workers` threads (at least one) and room for `max_waiting` jobs.
    ///
    /// # Errors
    /// The I/O error when a thread cannot be started.
    pub fn new(workers: usize, max_waiting: usize) -> std::io::Result<Self> {
        let inner = Arc::new(Inner {
            state: Mutex::new(State::default()),
            ready: Condvar::new(),
            max_waiting: max_waiting.max(1),
        });
        let workers = workers.max(1);
        // Built first, so that when a thread cannot be started, dropping it shuts down
        // those already started.
        let queue = Self {
            inner,
            workers,
            threads: Mutex::new(Vec::with_capacity(workers)),
        };
        for k in 0..workers {
            let inner = queue.inner.clone();
            let thread = std::thread::Builder::new()
                .name(format!("ivlmap-model-{k}"))
                .spawn(move || work(&inner))?;
            queue
                .threads
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .push(thread);
        }
        Ok(queue)
    }

    /// Queues `job`; `position` hears where it stands (now, and at every change) and
    /// `wanted` is asked just before it runs.
    ///
    /// # Errors
    /// [`QueueError::Full`] when `max_waiting` jobs wait already, [`QueueError::Closed`]
    /// after [`ModelQueue::shutdown`].
    pub fn push(&self, job: Job, position: PositionFn, wanted: WantedFn) -> Result<(), QueueError> {
        let mut st = self.inner.lock();
        if st.closed {
            return Err(QueueError::Closed);
        }
        if st.waiting.len() >= self.inner.max_waiting {
            return Err(QueueError::Full {
                waiting: st.waiting.len(),
            });
        }
        position(Some(st.waiting.len() + 1));
        st.waiting.push_back(Entry {
            job,
            position,
            wanted,
        });
        drop(st);
        self.inner.ready.notify_one();
        Ok(())
    }

    /// Counts.
    #[must_use]
    pub fn stats(&self) -> QueueStats {
        let st = self.inner.lock();
        QueueStats {
            waiting: st.waiting.len(),
            running: st.running,
            workers: self.workers,
            served: st.served,
            dropped: st.dropped,
        }
    }

    /// Takes no more jobs, drops the waiting ones unrun (their requesters see their answer
    /// channel close), and waits until the running ones have finished and the threads
    /// have exited. A second call returns at once. It blocks: call it off the async
    /// runtime. Called from one of the queue's own threads (a job holding the last
    /// reference), it waits for the others only.
    pub fn shutdown(&self) {
        let unrun = {
            let mut st = self.inner.lock();
            st.closed = true;
            let unrun = std::mem::take(&mut st.waiting);
            st.dropped += unrun.len() as u64;
            unrun
        };
        self.inner.ready.notify_all();
        // Outside the lock: dropping a job runs its captures' destructors.
        drop(unrun);
        let threads = std::mem::take(
            &mut *self
                .threads
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner),
        );
        let me = std::thread::current().id();
        for t in threads {
            if t.thread().id() != me {
                // A job's panic is caught inside the thread: join only fails on a panic
                // in the queue's own code, which has nothing left to clean up.
                let _ = t.join();
            }
        }
    }
}

impl Drop for ModelQueue {
    fn drop(&mut self) {
        self.shutdown();
    }
}

fn work(inner: &Inner) {
    loop {
        let entry = {
            let mut st = inner.lock();
            loop {
                if let Some(e) = st.waiting.pop_front() {
                    break e;
                }
                if st.closed {
                    return;
                }
                st = inner
                    .ready
                    .wait(st)
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
            }
        };
        let wanted = (entry.wanted)();
        {
            let mut st = inner.lock();
            for (i, e) in st.waiting.iter().enumerate() {
                (e.position)(Some(i + 1));
            }
            if wanted {
                st.running += 1;
            } else {
                st.dropped += 1;
            }
        }
        if !wanted {
            continue;
        }
        (entry.position)(None);
        // A panicking job drops its answer channel (its requester sees a failure); the
        // worker goes on.
        let outcome = std::panic::catch_unwind(AssertUnwindSafe(entry.job));
        if outcome.is_err() {
            tracing::error!("a model job panicked; its request failed, the server goes on");
        }
        let mut st = inner.lock();
        st.running = st.running.saturating_sub(1);
        st.served += 1;
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::panic)]
    use super::*;
    use std::sync::mpsc;
    use std::time::Duration;

    #[test]
    fn first_come_first_served_with_positions() {
        let q = ModelQueue::new(1, 8).unwrap();
        let (done_tx, done_rx) = mpsc::channel::<usize>();
        let positions = Arc::new(Mutex::new(Vec::<(usize, Option<usize>)>::new()));
        // Job 0 holds the only worker until the gate opens.
        let d = done_tx.clone();
        let gate_tx = hold_the_worker(&q, move || d.send(0).unwrap());
        for k in 1..=3 {
            let d = done_tx.clone();
            let p = positions.clone();
            q.push(
                Box::new(move || d.send(k).unwrap()),
                Box::new(move |pos| p.lock().unwrap().push((k, pos))),
                Box::new(move || k != 2), // job 2's requester has gone
            )
            .unwrap();
        }
        assert_eq!(q.stats().waiting, 3);
        gate_tx.send(()).unwrap();
        let order: Vec<usize> = (0..3)
            .map(|_| done_rx.recv_timeout(Duration::from_secs(10)).unwrap())
            .collect();
        assert_eq!(order, vec![0, 1, 3]);
        let p = positions.lock().unwrap().clone();
        assert!(
            p.contains(&(3, Some(3))) && p.contains(&(3, Some(2))) && p.contains(&(3, Some(1)))
        );
        assert!(p.contains(&(1, None)) && !p.contains(&(2, None)));
        wait_until(|| q.stats().served == 3);
        let s = q.stats();
        assert_eq!((s.served, s.dropped, s.waiting, s.running), (3, 1, 0, 0));
    }

    /// Queues a job that holds a worker until the returned gate opens (or 10 s pass),
    /// then runs `then`; returns once it runs.
    fn hold_the_worker(q: &ModelQueue, then: impl FnOnce() + Send + 'static) -> mpsc::Sender<()> {
        let (gate_tx, gate_rx) = mpsc::channel::<()>();
        let gate = Mutex::new(gate_rx);
        q.push(
            Box::new(move || {
                let _ = gate.lock().unwrap().recv_timeout(Duration::from_secs(10));
                then();
            }),
            Box::new(|_| {}),
            Box::new(|| true),
        )
        .unwrap();
        wait_until(|| q.stats().running == 1);
        gate_tx
    }

    fn wait_until(what: impl Fn() -> bool) {
        let t0 = std::time::Instant::now();
        while !what() {
            assert!(t0.elapsed() < Duration::from_secs(20), "timed out");
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn full_queue_refuses_and_a_panic_spares_the_worker() {
        let q = ModelQueue::new(1, 1).unwrap();
        let (tx, rx) = mpsc::channel::<u8>();
        q.push(
            Box::new(|| panic!("boom")),
            Box::new(|_| {}),
            Box::new(|| true),
        )
        .unwrap();
        wait_until(|| q.stats().served == 1);
        let t = tx.clone();
        let gate_tx = hold_the_worker(&q, move || t.send(1).unwrap());
        let t = tx.clone();
        q.push(
            Box::new(move || t.send(2).unwrap()),
            Box::new(|_| {}),
            Box::new(|| true),
        )
        .unwrap();
        let err = q
            .push(Box::new(|| {}), Box::new(|_| {}), Box::new(|| true))
            .unwrap_err();
        assert_eq!(err, QueueError::Full { waiting: 1 });
        gate_tx.send(()).unwrap();
        assert_eq!(rx.recv_timeout(Duration::from_secs(10)).unwrap(), 1);
        assert_eq!(rx.recv_timeout(Duration::from_secs(10)).unwrap(), 2);
    }

    #[test]
    fn shutdown_waits_for_the_running_job_and_drops_the_waiting() {
        let q = Arc::new(ModelQueue::new(1, 8).unwrap());
        let finished = Arc::new(Mutex::new(Vec::<u8>::new()));
        let f = finished.clone();
        let gate_tx = hold_the_worker(&q, move || f.lock().unwrap().push(1));
        let f = finished.clone();
        q.push(
            Box::new(move || f.lock().unwrap().push(2)),
            Box::new(|_| {}),
            Box::new(|| true),
        )
        .unwrap();
        // The gate opens only once shutdown has dropped the waiting job: the running one
        // is still running while shutdown waits.
        let opener = {
            let q = q.clone();
            std::thread::spawn(move || {
                wait_until(|| q.stats().dropped == 1);
                gate_tx.send(()).unwrap();
            })
        };
        q.shutdown();
        assert_eq!(*finished.lock().unwrap(), vec![1]);
        let s = q.stats();
        assert_eq!((s.served, s.dropped, s.waiting, s.running), (1, 1, 0, 0));
        let err = q
            .push(Box::new(|| {}), Box::new(|_| {}), Box::new(|| true))
            .unwrap_err();
        assert_eq!(err, QueueError::Closed);
        q.shutdown();
        opener.join().unwrap();
    }
}
