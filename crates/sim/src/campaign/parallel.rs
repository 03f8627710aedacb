//! Runs spread over the machine's cores: each run builds its own rigs,
//! so they share nothing but the device configuration.

/// `each` over `items` on the machine's cores (at most 8 threads), calling
/// `done` after each; the results in the items' order. A worker that
/// panicked loses its items; the result is then shorter than `items`,
/// which the callers check.
pub(super) fn on_every_core<T: Sync, R: Send>(
    items: &[T],
    each: impl Fn(&T) -> R + Sync,
    done: &(dyn Fn() + Sync),
) -> Vec<R> {
    let workers = std::thread::available_parallelism().map_or(2, |n| n.get().clamp(1, 8));
    let each = &each;
    let mut parts: Vec<Vec<(usize, R)>> = Vec::new();
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..workers)
            .map(|w| {
                s.spawn(move || {
                    items
                        .iter()
                        .enumerate()
                        .skip(w)
                        .step_by(workers)
                        .map(|(i, item)| {
                            let result = each(item);
                            done();
                            (i, result)
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        for h in handles {
            if let Ok(part) = h.join() {
                parts.push(part);
            }
        }
    });
    let mut all: Vec<(usize, R)> = parts.into_iter().flatten().collect();
    all.sort_by_key(|(i, _)| *i);
    all.into_iter().map(|(_, r)| r).collect()
}
