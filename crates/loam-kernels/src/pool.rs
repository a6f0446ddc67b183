//! Where a step runs: on a thread of rayon's pool (docs/theory.md §7).

/// `op` run on a thread of rayon's pool, handed over once, or `None` where the caller is
/// already on one (of any pool) and should go on itself. Each analysis's `step` starts with
/// it, so that its parallel passes (a dozen or more a step) start on a worker instead of
/// each being handed to the pool from outside and waiting for a sleeping worker: about
/// 20 µs a pass on a 2-core machine, most of a small problem's step.
pub fn on_pool<R: Send>(op: impl FnOnce() -> R + Send) -> Option<R> {
    rayon::current_thread_index().is_none().then(|| rayon::scope(|_| op()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// From outside any pool the work runs on a worker; on a worker it is left to the caller.
    #[test]
    fn hands_over_only_from_outside_the_pool() {
        assert_eq!(rayon::current_thread_index(), None);
        assert!(matches!(on_pool(rayon::current_thread_index), Some(Some(_))));
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        assert_eq!(pool.install(|| on_pool(|| ())), None);
    }
}
