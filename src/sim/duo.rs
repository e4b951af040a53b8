//! Two threads forking and joining every step by spinning, for a loop whose steps
//! are too short for a thread pool's hand-over.
//!
//! `rayon::join` wakes an idle worker for the second half of the work; on some
//! machines that takes longer than the first half of a small step (measured: a
//! 128 x 128 grid stepped 0.96x as fast on two threads as on one, while two
//! single-thread runs at once each kept their speed). A [`Duo`] lives for a run of
//! steps: one thread calls [`Duo::fork`] each step, the other sits in
//! [`Duo::serve`], spinning, and takes the second half as soon as it is posted. If
//! the server has not taken it by the time the first half is done, the caller takes
//! it back and runs it itself, so a server that never starts (or starts late) costs
//! time, never correctness: nothing waits on a job that nobody has taken.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// A job posted by [`Duo::fork`]: the second half, borrowed from the caller's stack
/// for as long as the caller waits for it, and its number.
struct Posted(*mut (dyn FnMut() + Send + 'static), u64);

// SAFETY: the closure behind the pointer is `Send`, and `fork` keeps it alive and
// untouched until the thread that took it reports it done.
unsafe impl Send for Posted {}

/// The hand-over between the stepping thread and the serving one.
#[derive(Default)]
pub(crate) struct Duo {
    /// The job waiting to be taken, if any.
    slot: Mutex<Option<Posted>>,
    /// Jobs posted so far (lets the server poll without the lock).
    posted: AtomicU64,
    /// Jobs the server has finished.
    finished: AtomicU64,
    /// Set by [`Duo::finish`]: the server returns.
    done: AtomicBool,
}

impl Duo {
    /// Runs `first` on this thread and `second` on the serving thread if it takes it
    /// in time (else here, after `first`), and returns when both are done.
    pub fn fork(&self, second: &mut (dyn FnMut() + Send), first: impl FnOnce()) {
        let ptr: *mut (dyn FnMut() + Send + '_) = second;
        // SAFETY: only the lifetime is erased. The pointer is used either by this
        // thread below, or by the server before it bumps `finished`, which this
        // function waits for; `second` outlives both.
        let ptr: *mut (dyn FnMut() + Send + 'static) = unsafe { std::mem::transmute(ptr) };
        let number = self.posted.load(Ordering::Relaxed) + 1;
        *self.lock() = Some(Posted(ptr, number));
        self.posted.store(number, Ordering::Release);
        first();
        if self.lock().take().is_some() {
            // Not taken: run it here.
            second();
            self.finished.store(number, Ordering::Release);
        } else {
            let mut wait = Backoff::default();
            while self.finished.load(Ordering::Acquire) < number {
                wait.pause();
            }
        }
    }

    /// [`Duo::fork`] with a second half that runs once.
    pub fn fork_once(&self, second: impl FnOnce() + Send, first: impl FnOnce()) {
        let mut second = Some(second);
        self.fork(
            &mut || {
                if let Some(second) = second.take() {
                    second();
                }
            },
            first,
        );
    }

    /// Takes and runs posted jobs until [`Duo::finish`] is called.
    pub fn serve(&self) {
        let (mut seen, mut wait) = (0, Backoff::default());
        while !self.done.load(Ordering::Acquire) {
            let posted = self.posted.load(Ordering::Acquire);
            if posted == seen {
                wait.pause();
                continue;
            }
            (seen, wait) = (posted, Backoff::default());
            let job = self.lock().take();
            if let Some(Posted(job, number)) = job {
                // SAFETY: see `fork`: the caller waits for `finished` to reach the
                // job's number before the closure goes out of scope.
                let ran =
                    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| unsafe { (*job)() }));
                // Reported even after a panic, so that the caller never waits for
                // it; the panic then goes on from here.
                self.finished.store(number, Ordering::Release);
                if let Err(panic) = ran {
                    std::panic::resume_unwind(panic);
                }
            }
        }
    }

    /// Tells the server to return.
    pub fn finish(&self) {
        self.done.store(true, Ordering::Release);
    }

    /// A guard that calls [`Duo::finish`] when dropped, also when unwinding.
    pub fn finish_on_drop(&self) -> impl Drop + '_ {
        struct Finish<'a>(&'a Duo);
        impl Drop for Finish<'_> {
            fn drop(&mut self) {
                self.0.finish();
            }
        }
        Finish(self)
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Option<Posted>> {
        // A panic inside a job is carried by the thread that ran it; the slot
        // itself is always left consistent.
        self.slot.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// Runs `run` inside `pool` (on this thread when there is none). With `spin` (and
/// a pool), the pool's other worker serves a [`Duo`] for the whole run, and `run`
/// is given it to fork each step's second half to; the server returns when `run`
/// does, also when it panics.
pub(crate) fn run_in_pool(
    pool: Option<&rayon::ThreadPool>,
    spin: bool,
    mut run: impl FnMut(Option<&Duo>) + Send,
) {
    match pool {
        Some(pool) if spin => {
            let duo = Duo::default();
            pool.install(|| {
                rayon::join(
                    || {
                        let _finish = duo.finish_on_drop();
                        run(Some(&duo));
                    },
                    || duo.serve(),
                )
            });
        }
        Some(pool) => pool.install(|| run(None)),
        None => run(None),
    }
}

/// Spins a while, then yields the core at each pause: two threads that the
/// system has put on one core (as it may at the start of a run, before it spreads
/// them) then take turns at once instead of each spinning out its time slice.
#[derive(Default)]
struct Backoff(u32);

impl Backoff {
    /// Spins this many times before yielding.
    const SPINS: u32 = 256;

    fn pause(&mut self) {
        if self.0 < Self::SPINS {
            self.0 += 1;
            std::hint::spin_loop();
        } else {
            std::thread::yield_now();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each step's two sums, and how many second halves ran on another thread.
    fn sums(duo: &Duo, steps: usize) -> (Vec<(u64, u64)>, usize) {
        let (mut out, mut elsewhere) = (Vec::new(), 0);
        let here = std::thread::current().id();
        for step in 0..steps as u64 {
            let (mut a, mut b, mut thread) = (0, 0, here);
            let mut second = || {
                b = (0..1000).map(|i| std::hint::black_box(i * step)).sum();
                thread = std::thread::current().id();
            };
            duo.fork(&mut second, || {
                a = (0..1000).map(|i| std::hint::black_box(i + step)).sum()
            });
            out.push((a, b));
            elsewhere += usize::from(thread != here);
        }
        (out, elsewhere)
    }

    fn expected(steps: usize) -> Vec<(u64, u64)> {
        (0..steps as u64)
            .map(|s| {
                (
                    (0..1000).map(|i| i + s).sum(),
                    (0..1000).map(|i| i * s).sum(),
                )
            })
            .collect()
    }

    #[test]
    fn with_a_server_every_step_gets_both_halves() {
        let duo = Duo::default();
        let started = AtomicBool::new(false);
        let (got, elsewhere) = std::thread::scope(|scope| {
            scope.spawn(|| {
                started.store(true, Ordering::Release);
                duo.serve();
            });
            while !started.load(Ordering::Acquire) {
                std::thread::yield_now();
            }
            // Rounds of steps until the server has taken a job (it spins the
            // whole time, so the first round nearly always does), for at most
            // about ten seconds on a loaded machine.
            let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
            loop {
                let (got, elsewhere) = sums(&duo, 2000);
                if elsewhere > 0 || std::time::Instant::now() > deadline {
                    duo.finish();
                    break (got, elsewhere);
                }
            }
        });
        assert_eq!(got, expected(2000));
        assert!(elsewhere > 0, "no job ran on the server");
    }

    #[test]
    fn without_a_server_the_caller_runs_both_halves() {
        let duo = Duo::default();
        assert_eq!(sums(&duo, 50), (expected(50), 0));
        // A server that starts after the work returns at once.
        duo.finish();
        duo.serve();
    }
}
