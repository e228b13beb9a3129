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

/// Wait for a condition that a future made by `make` resolves on, up to `limit` in all,
/// making a fresh future every `slice`. For futures that can miss their wake-up:
/// ros2-client's `wait_for_service` checks the match state once, then waits for a
/// graph event on a channel of 8 that drops what does not fit (`try_send`); a burst of
/// discovery events on a loaded machine can drop the one it waits for, and then it
/// waits forever (seen in CI: `NoActionServer` after 20 s with the stand-in up). A
/// fresh future checks the match state again.
pub(crate) fn with_retries<F: Future>(
    mut make: impl FnMut() -> F,
    limit: Duration,
    slice: Duration,
) -> Option<F::Output> {
    let t0 = std::time::Instant::now();
    loop {
        let left = limit.saturating_sub(t0.elapsed());
        if left.is_zero() {
            return None;
        }
        if let Some(v) = with_timeout(make(), left.min(slice)) {
            return Some(v);
        }
    }
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

    #[test]
    fn a_future_that_missed_its_wake_up_is_made_again_until_the_limit() {
        // The first two futures never resolve (a missed wake-up); the third is ready.
        let mut made = 0;
        let got = with_retries(
            || {
                made += 1;
                let ready = made >= 3;
                async move {
                    if !ready {
                        futures::future::pending::<()>().await;
                    }
                    made
                }
            },
            Duration::from_secs(60),
            Duration::from_millis(10),
        );
        assert_eq!(got, Some(3));
        // Never ready: gives up at the limit, having made a fresh future each slice.
        let t0 = std::time::Instant::now();
        let mut tries = 0;
        let none = with_retries(
            || {
                tries += 1;
                futures::future::pending::<()>()
            },
            Duration::from_millis(100),
            Duration::from_millis(10),
        );
        assert_eq!(none, None);
        assert!(tries >= 2, "{tries}");
        assert!(t0.elapsed() >= Duration::from_millis(100));
    }
}
