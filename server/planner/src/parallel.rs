//! Work shared out over the cores in consecutive chunks, results in order: what a caller gets never depends
//! on the number of threads (each item is computed alone, sequentially).

/// `f(i)` for every `i < n`, in order; the indices split into one consecutive chunk per core (at most 8).
pub(crate) fn map_indexed<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let threads = std::thread::available_parallelism()
        .map_or(1, usize::from)
        .clamp(1, 8)
        .min(n.max(1));
    let chunk = n.div_ceil(threads).max(1);
    let f = &f;
    std::thread::scope(|scope| {
        let handles: Vec<_> = (0..n)
            .step_by(chunk)
            .map(|lo| scope.spawn(move || (lo..(lo + chunk).min(n)).map(f).collect::<Vec<T>>()))
            .collect();
        let mut out = Vec::with_capacity(n);
        for h in handles {
            out.extend(h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)));
        }
        out
    })
}

#[cfg(test)]
mod tests {
    use super::map_indexed;

    #[test]
    fn results_come_in_order_whatever_the_count() {
        for n in [0, 1, 2, 7, 1000] {
            assert_eq!(map_indexed(n, |i| i * i), (0..n).map(|i| i * i).collect::<Vec<_>>());
        }
    }
}
