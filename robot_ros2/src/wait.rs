//! Waiting on a future with a deadline, outside any async runtime.

use std::future::Future;
use std::sync::mpsc;
use std::time::Duration;

use futures::future::{select, Either};

/// Run `fut` to completion, or give up after `limit` (`None`). The timer is a thread
/// that leaves as soon as either side is done.
pub(crate) fn with_timeout<F: Future>(fut: F, limit: Duration) -> Option<F::Output> {
    let (fire_tx, fire_rx) = futures::channel::oneshot::channel::<()>();
    let (done_tx, done_rx) = mpsc::channel::<()>();
    let timer = std::thread::Builder::new()
        .name("ros2-timeout".into())
        .spawn(move || {
            if let Err(mpsc::RecvTimeoutError::Timeout) = done_rx.recv_timeout(limit) {
                let _ = fire_tx.send(());
            }
        });
    if timer.is_err() {
        return None;
    }
    let out = futures::executor::block_on(async {
        let fut = std::pin::pin!(fut);
        match select(fut, fire_rx).await {
            Either::Left((v, _)) => Some(v),
            Either::Right(_) => None,
        }
    });
    drop(done_tx);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ready_future_is_returned_and_a_pending_one_times_out() {
        assert_eq!(with_timeout(async { 7 }, Duration::from_secs(60)), Some(7));
        let never = futures::future::pending::<()>();
        assert_eq!(with_timeout(never, Duration::from_millis(20)), None);
    }
}
