//! One implementation of the clients and the drive for both flavours: the code is written once,
//! `async`, over the [`Wire`] trait; the async flavour awaits it over an
//! [`AsyncTransport`](crate::async_client::AsyncTransport), the blocking one runs the same
//! futures with [`block_on`] over a blocking [`Transport`], whose futures are ready at their
//! first poll.

use std::future::Future;
use std::io;
use std::pin::pin;
use std::task::{Context, Poll, Waker};
use std::time::{Duration, Instant};

use crate::transport::Transport;

/// A link and the clock, as the one implementation of the clients and the drive sees them:
/// [`Transport`]'s methods and the two waits, `async`.
// The futures are not promised `Send`: like `AsyncTransport`'s, they run on the task (or the
// thread) that drives the client.
#[allow(async_fn_in_trait)]
pub(crate) trait Wire {
    /// The longest gap allowed between two bytes of one frame, if the link keeps byte timing.
    fn inter_char_timeout(&self) -> Option<Duration>;
    /// Sends one whole frame.
    async fn send(&mut self, frame: &[u8]) -> io::Result<()>;
    /// Receives available bytes, waiting until at least one arrives or `deadline` passes
    /// (then returns 0).
    async fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize>;
    /// Throws away bytes received but not yet read.
    async fn discard_input(&mut self) -> io::Result<()>;
    /// Re-establishes a connection the peer closed or reset.
    async fn reconnect(&mut self) -> io::Result<()>;
    /// Waits until `at` (the gap before a request), which has not passed yet.
    async fn sleep_until(&mut self, at: Instant);
    /// Waits `d` (between two reads of a command profile's status word).
    async fn pause(&mut self, d: Duration);
}

/// A blocking [`Transport`] as a [`Wire`]: every future completes at its first poll, having done
/// the blocking call (and the blocking sleep) inside it.
pub(crate) struct Blocking<'a, T>(pub(crate) &'a mut T);

impl<T: Transport> Wire for Blocking<'_, T> {
    fn inter_char_timeout(&self) -> Option<Duration> {
        self.0.inter_char_timeout()
    }

    async fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        self.0.send(frame)
    }

    async fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        self.0.recv(buf, deadline)
    }

    async fn discard_input(&mut self) -> io::Result<()> {
        self.0.discard_input()
    }

    async fn reconnect(&mut self) -> io::Result<()> {
        self.0.reconnect()
    }

    async fn sleep_until(&mut self, at: Instant) {
        std::thread::sleep(at.saturating_duration_since(Instant::now()));
    }

    async fn pause(&mut self, d: Duration) {
        std::thread::sleep(d);
    }
}

/// An [`AsyncTransport`](crate::async_client::AsyncTransport) as a [`Wire`], waiting on tokio's
/// timer.
#[cfg(feature = "tokio")]
pub(crate) struct Tokio<'a, T>(pub(crate) &'a mut T);

#[cfg(feature = "tokio")]
impl<T: crate::async_client::AsyncTransport> Wire for Tokio<'_, T> {
    fn inter_char_timeout(&self) -> Option<Duration> {
        self.0.inter_char_timeout()
    }

    async fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        self.0.send(frame).await
    }

    async fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        self.0.recv(buf, deadline).await
    }

    async fn discard_input(&mut self) -> io::Result<()> {
        self.0.discard_input().await
    }

    async fn reconnect(&mut self) -> io::Result<()> {
        self.0.reconnect().await
    }

    async fn sleep_until(&mut self, at: Instant) {
        // Only called while the gap is still to come: a sleep registers a timer even for an
        // instant that has passed, and tokio's timer rounds it up to its 1 ms tick.
        tokio::time::sleep_until(tokio::time::Instant::from_std(at)).await;
    }

    async fn pause(&mut self, d: Duration) {
        tokio::time::sleep(d).await;
    }
}

/// Runs a future of the blocking flavour (one over [`Blocking`]) to its end on this thread.
///
/// Hand-written on purpose, and all an executor needs to be here: every future of the blocking
/// flavour is ready at its first poll (the blocking calls and sleeps are made inside
/// [`Blocking`]'s methods, nothing waits for a waker), so a waker that does nothing is enough,
/// and no executor crate is needed. Nothing is allocated (the future is pinned on the stack),
/// so a blocking transaction still allocates nothing. Should a future ever be pending (none
/// of this crate's is), it is polled again, after giving up the thread's time slice.
pub(crate) fn block_on<F: Future>(future: F) -> F::Output {
    let mut future = pin!(future);
    let mut cx = Context::from_waker(Waker::noop());
    loop {
        if let Poll::Ready(output) = future.as_mut().poll(&mut cx) {
            return output;
        }
        std::thread::yield_now();
    }
}
