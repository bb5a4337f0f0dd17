//! The worker pool: [`run_jobs`] runs a slice of jobs on N scoped threads that take
//! the next job index from a shared counter; the results come back in job order, and
//! the caller's thread gets a [`Progress`] callback as each job finishes (a progress
//! bar needs nothing more). Batches and sweeps run on it.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;
use std::thread;

/// A finished job, as [`run_jobs`] reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    /// The job's index in the slice.
    pub job: usize,
    /// Jobs finished so far, this one included (1..=`total`).
    pub done: usize,
    /// Jobs in all.
    pub total: usize,
}

/// Runs `work(k, &jobs[k])` for every job on `threads` worker threads (at least 1, at
/// most one per job) and returns the results in job order, whatever order they finish
/// in. `progress` is called on the caller's thread once per job, as each one finishes
/// (so it may hold non-`Send` state such as a terminal handle).
///
/// The workers take the next job index from a shared atomic counter, so a long job
/// does not hold up the others; a result travels back to the caller with its index.
/// A panic in `work` or `progress` is resumed on the caller's thread once every worker
/// has stopped.
pub fn run_jobs<J, R, W, P>(jobs: &[J], threads: usize, work: W, mut progress: P) -> Vec<R>
where
    J: Sync,
    R: Send,
    W: Fn(usize, &J) -> R + Sync,
    P: FnMut(Progress, &R),
{
    let total = jobs.len();
    let workers = threads.clamp(1, total.max(1));
    let next = AtomicUsize::new(0);
    let mut results: Vec<Option<R>> = (0..total).map(|_| None).collect();
    thread::scope(|scope| {
        let (tx, rx) = mpsc::channel();
        for _ in 0..workers {
            let tx = tx.clone();
            let (next, work) = (&next, &work);
            scope.spawn(move || loop {
                // Relaxed is enough: the counter only hands out distinct indices; the
                // results reach the caller through the channel, which synchronizes.
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some(job) = jobs.get(k) else { break };
                if tx.send((k, work(k, job))).is_err() {
                    // The caller stopped listening (its progress callback panicked).
                    break;
                }
            });
        }
        // The workers hold the only senders left: the loop ends when they all stop.
        drop(tx);
        for (done, (job, result)) in rx.iter().enumerate() {
            progress(
                Progress {
                    job,
                    done: done + 1,
                    total,
                },
                &result,
            );
            results[job] = Some(result);
        }
    });
    // Every index below `total` was taken by exactly one worker, and a worker that
    // panicked has made `thread::scope` panic above, so every slot is filled.
    results
        .into_iter()
        .map(|r| r.expect("every job reported its result"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    // The results come back in job order although later jobs finish first, and the
    // progress callback sees every job once.
    #[test]
    fn results_in_job_order_whatever_the_finishing_order() {
        let jobs: Vec<u64> = (0..12).collect();
        for threads in [1, 2, 3, 64] {
            let mut seen = Vec::new();
            let out = run_jobs(
                &jobs,
                threads,
                |k, &j| {
                    // The first job is by far the longest: with 2 threads or more,
                    // the others finish while it runs.
                    thread::sleep(Duration::from_millis(if j == 0 { 100 } else { 1 }));
                    (k, j * j)
                },
                |p, r: &(usize, u64)| {
                    assert_eq!(p.job, r.0);
                    assert_eq!(p.total, 12);
                    seen.push((p.done, p.job));
                },
            );
            let want: Vec<(usize, u64)> = jobs.iter().map(|&j| (j as usize, j * j)).collect();
            assert_eq!(out, want, "{threads} threads");
            assert_eq!(
                seen.iter().map(|s| s.0).collect::<Vec<_>>(),
                (1..=12).collect::<Vec<_>>()
            );
            let mut order: Vec<usize> = seen.iter().map(|s| s.1).collect();
            if threads > 1 {
                // The long first job finished after a later one.
                assert_ne!(order[0], 0, "{threads} threads: {order:?}");
            }
            order.sort_unstable();
            assert_eq!(order, (0..12).collect::<Vec<_>>());
        }
    }

    #[test]
    fn no_jobs() {
        let out: Vec<u8> = run_jobs(&[] as &[u8], 2, |_, &j| j, |_, _| panic!("no job"));
        assert!(out.is_empty());
    }
}
