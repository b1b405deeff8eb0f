//! Independent work of one diagnosis on every core: [`map`] runs a function over items on
//! scoped threads (no I/O; nothing kept between calls but the count of helper threads running)
//! and returns the results in the items' order, so that the diagnosis is the same whatever the
//! number of cores. Used for the folds'
//! refits ([`crate::folds::cross_validate`]) and the candidates of a forward step and of a
//! revision ([`crate::search`], [`crate::revise`]).

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Helper threads of every [`map`] running now: a [`map`] inside another's item (a candidate's
/// grid of fits inside a forward step) takes only the cores left idle.
static HELPERS: AtomicUsize = AtomicUsize::new(0);

/// Releases a helper's place in [`HELPERS`] when it ends (also when its item panics).
struct Place;

impl Drop for Place {
    fn drop(&mut self) {
        HELPERS.fetch_sub(1, Ordering::AcqRel);
    }
}

/// Takes up to `want` places for helper threads among the cores the running ones leave idle.
fn take_places(want: usize) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut got = 0;
    while got < want {
        let now = HELPERS.load(Ordering::Acquire);
        if 1 + now >= cores {
            break;
        }
        if HELPERS
            .compare_exchange(now, now + 1, Ordering::AcqRel, Ordering::Acquire)
            .is_ok()
        {
            got += 1;
        }
    }
    got
}

/// `items.iter().map(f).collect()`, the items shared out over the calling thread and helper
/// threads on the cores no other [`map`] holds (each thread takes the next item not yet
/// taken); on the calling thread alone when every core is busy. A panic in `f` is raised again
/// on the calling thread.
pub fn map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let helpers = take_places(items.len().saturating_sub(1));
    if helpers == 0 {
        return items.iter().map(f).collect();
    }
    let next = AtomicUsize::new(0);
    let done: Mutex<Vec<(usize, R)>> = Mutex::new(Vec::with_capacity(items.len()));
    let work = || {
        let mut mine = Vec::new();
        loop {
            let i = next.fetch_add(1, Ordering::Relaxed);
            let Some(item) = items.get(i) else { break };
            mine.push((i, f(item)));
        }
        done.lock().unwrap_or_else(|e| e.into_inner()).extend(mine);
    };
    std::thread::scope(|s| {
        let spawned: Vec<_> = (0..helpers)
            .map(|_| {
                s.spawn(move || {
                    let _place = Place;
                    work()
                })
            })
            .collect();
        work();
        for h in spawned {
            if let Err(e) = h.join() {
                std::panic::resume_unwind(e);
            }
        }
    });
    let mut done = done.into_inner().unwrap_or_else(|e| e.into_inner());
    done.sort_by_key(|d| d.0);
    done.into_iter().map(|d| d.1).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_come_back_in_the_items_order_even_when_nested() {
        let items: Vec<usize> = (0..37).collect();
        let got = map(&items, |&i| {
            let inner: Vec<usize> = (0..i % 5).collect();
            i * 10 + map(&inner, |&j| j).iter().sum::<usize>()
        });
        let want: Vec<usize> = items
            .iter()
            .map(|&i| i * 10 + (0..i % 5).sum::<usize>())
            .collect();
        assert_eq!(got, want);
        assert!(map(&Vec::<u8>::new(), |&b| b).is_empty());
    }
}
