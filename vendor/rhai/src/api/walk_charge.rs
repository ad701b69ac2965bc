//! Charging the work of data-size checks as operations (a critterbox patch, see `PATCH.md`).
//!
//! With a size limit set, the engine measures an array or map after every operation that may
//! change it (a method call on it, an indexed assignment), walking every item. A loop of cheap
//! method calls on a large array then does far more work than its operation count says, so
//! `max_operations` no longer bounds a call's time. With a charge set, every `items_per_op`
//! items walked count as one operation more, towards `max_operations` and in the count passed
//! to `on_progress`.
#![cfg(not(feature = "unchecked"))]

use crate::Engine;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// The charge's rate and what it has counted.
#[derive(Debug)]
pub(crate) struct WalkCharge {
    /// Items walked per operation charged.
    items_per_op: u64,
    /// Items walked and not yet charged, within the running call.
    walked: AtomicU64,
    /// Operations charged in all, for the engine's user.
    charged: Arc<AtomicU64>,
}

impl WalkCharge {
    /// Notes `items` walked by a data-size check.
    #[inline(always)]
    pub(crate) fn walked(&self, items: usize) {
        // Most checks walk nothing (a number, a custom type): no locked add for them.
        if items != 0 {
            self.walked.fetch_add(items as u64, Ordering::Relaxed);
        }
    }

    /// The operations to charge now. A call's first operation starts from nothing walked, so a
    /// call's count never depends on the calls before it.
    #[inline(always)]
    pub(crate) fn take(&self, first_of_call: bool) -> u64 {
        if first_of_call {
            self.walked.store(0, Ordering::Relaxed);
            return 0;
        }
        let walked = self.walked.load(Ordering::Relaxed);
        if walked < self.items_per_op {
            return 0;
        }
        self.walked
            .store(walked % self.items_per_op, Ordering::Relaxed);
        let ops = walked / self.items_per_op;
        self.charged.fetch_add(ops, Ordering::Relaxed);
        ops
    }
}

impl Engine {
    /// Charges one operation for every `items_per_op` items of arrays and maps the data-size
    /// checks walk (none with 0). Returns the count of operations charged in all, which grows as
    /// the engine runs: an `on_progress` callback that tallies operations across calls adds its
    /// growth to its own count.
    ///
    /// Not available under `unchecked`.
    pub fn set_data_walk_charge(&mut self, items_per_op: u64) -> Arc<AtomicU64> {
        let charged = Arc::new(AtomicU64::new(0));
        self.walk_charge = (items_per_op > 0).then(|| WalkCharge {
            items_per_op,
            walked: AtomicU64::new(0),
            charged: charged.clone(),
        });
        charged
    }
}
