//! What changed since the renderer last looked: a small coalesced list of byte ranges per
//! GPU-mirrored buffer, so scattered edits re-upload only what they touched.
//!
//! Recording is an O(1) append (extending the last range when it touches it); the log is
//! sorted and merged only when it grows past twice its cap, and when merged ranges are still
//! too many, nearby ranges are merged across growing gaps. The list is therefore exact while
//! small and degrades towards slightly larger uploads, never towards lost ranges.

use std::ops::Range;

/// Ranges kept before nearby ones are merged across gaps.
pub const MAX_RANGES: usize = 256;

/// Byte ranges of one buffer that changed since the last drain.
#[derive(Clone, Debug, Default)]
pub struct DirtyRanges {
    log: Vec<Range<u64>>,
    /// Gaps up to this many bytes are merged away; grows when the list overflows.
    gap: u64,
}

impl DirtyRanges {
    /// Records that `range` changed.
    #[inline]
    pub fn record(&mut self, range: Range<u64>) {
        if range.is_empty() {
            return;
        }
        if let Some(last) = self.log.last_mut()
            && range.start <= last.end + self.gap
            && range.end + self.gap >= last.start
        {
            last.start = last.start.min(range.start);
            last.end = last.end.max(range.end);
            return;
        }
        self.log.push(range);
        if self.log.len() > 2 * MAX_RANGES {
            self.coalesce();
        }
    }

    /// Records every range of `other`.
    pub fn extend(&mut self, other: &DirtyRanges) {
        for r in &other.log {
            self.record(r.clone());
        }
    }

    fn coalesce(&mut self) {
        loop {
            self.log.sort_unstable_by_key(|r| r.start);
            let mut out: Vec<Range<u64>> = Vec::with_capacity(self.log.len());
            for r in self.log.drain(..) {
                match out.last_mut() {
                    Some(last) if r.start <= last.end + self.gap => last.end = last.end.max(r.end),
                    _ => out.push(r),
                }
            }
            self.log = out;
            if self.log.len() <= MAX_RANGES {
                return;
            }
            self.gap = (self.gap * 4).max(64);
        }
    }

    /// Whether nothing changed.
    pub fn is_empty(&self) -> bool {
        self.log.is_empty()
    }

    /// The sorted, merged ranges; the list is left empty.
    pub fn take(&mut self) -> Vec<Range<u64>> {
        self.coalesce();
        self.gap = 0;
        std::mem::take(&mut self.log)
    }

    /// Sorted, merged ranges without clearing.
    pub fn ranges(&self) -> Vec<Range<u64>> {
        let mut copy = self.clone();
        copy.take()
    }

    /// Total bytes covered.
    pub fn bytes(&self) -> u64 {
        self.ranges().iter().map(|r| r.end - r.start).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merges_touching_and_keeps_scattered_apart() {
        let mut d = DirtyRanges::default();
        d.record(0..4);
        d.record(4..8);
        d.record(1000..1004);
        d.record(2..6);
        assert_eq!(d.take(), vec![0..8, 1000..1004]);
        assert!(d.is_empty());
    }

    #[test]
    fn overflow_stays_small_and_covers_everything() {
        let mut d = DirtyRanges::default();
        let mut covered = vec![false; 200_000];
        for i in 0..5000u64 {
            let s = (i * 7919) % 199_000;
            d.record(s..s + 3);
            covered[s as usize..s as usize + 3]
                .iter_mut()
                .for_each(|c| *c = true);
        }
        let r = d.take();
        assert!(r.len() <= MAX_RANGES);
        for (i, c) in covered.iter().enumerate() {
            if *c {
                assert!(r.iter().any(|r| r.contains(&(i as u64))), "byte {i} lost");
            }
        }
        // Scattered edits must not degrade to one span over everything.
        let total: u64 = r.iter().map(|r| r.end - r.start).sum();
        assert!(total < 199_000, "total {total}");
    }
}
