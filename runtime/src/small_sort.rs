//! A stable sort of four items, as `slice::sort_by` sorts them, written
//! out so that it compiles inline.
//!
//! The eigen analysis sorts four roots, or four indices, at every speed
//! (the quartic's roots, the labelled roots' canonical order, the output
//! order). For so few items the standard library's stable sort is an
//! insertion sort, but a call of its own with the comparison a call too:
//! a twentieth of the browser's eigenvalue diagram in a profile
//! (2026-12-02). [`sort4_by`] is that insertion sort, comparison for
//! comparison (the same calls in the same order), so it gives the same
//! order whatever the comparison, a NaN's `Equal` fallback included.

use std::cmp::Ordering;

/// Sorts `a` by `cmp` as `a.sort_by(cmp)` does: each item from the second
/// on is moved left past the items it compares `Less` to.
#[inline(always)]
pub fn sort4_by<T: Copy>(a: &mut [T; 4], mut cmp: impl FnMut(&T, &T) -> Ordering) {
    for i in 1..4 {
        let x = a[i];
        let mut j = i;
        while j > 0 && cmp(&x, &a[j - 1]) == Ordering::Less {
            a[j] = a[j - 1];
            j -= 1;
        }
        a[j] = x;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::SplitMix64;

    /// The standard library's order, on every ordering of four keys with
    /// ties and NaN (whose `partial_cmp` falls back to `Equal`, which is no
    /// total order): each item's place as `sort_by` gives it, and the
    /// comparisons made in the same order.
    #[test]
    fn sorts_four_as_the_standard_library_does() {
        let keys = [0.0, -0.0, 1.0, f64::NAN, -2.0, 1.0];
        let mut rng = SplitMix64::new(20261202);
        for _ in 0..20_000 {
            let pick = |r: &mut SplitMix64| keys[(r.next_f64() * keys.len() as f64) as usize % keys.len()];
            let a: [(f64, usize); 4] = std::array::from_fn(|k| (pick(&mut rng), k));
            let cmp = |x: &(f64, usize), y: &(f64, usize)| y.0.partial_cmp(&x.0).unwrap_or(Ordering::Equal);
            let (mut seen_std, mut seen_ours) = (Vec::new(), Vec::new());
            let mut std_sorted = a;
            std_sorted.sort_by(|x, y| {
                seen_std.push((x.1, y.1));
                cmp(x, y)
            });
            let mut ours = a;
            sort4_by(&mut ours, |x, y| {
                seen_ours.push((x.1, y.1));
                cmp(x, y)
            });
            assert_eq!(std_sorted.map(|x| x.1), ours.map(|x| x.1), "{a:?}");
            assert_eq!(seen_std, seen_ours, "{a:?}");
        }
    }
}
