//! Bulk-in requests waiting for device data: one queue per endpoint, in submission order.

use std::collections::{BTreeMap, VecDeque};

/// A queued bulk-in request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PendingIn {
    /// The host's sequence number of the request.
    pub(crate) seqnum: u32,
    /// The most bytes the host accepts (`transfer_buffer_length`).
    pub(crate) max_len: usize,
}

/// Queued bulk-in requests by endpoint address.
#[derive(Debug, Default)]
pub(crate) struct PendingQueues {
    queues: BTreeMap<u8, VecDeque<PendingIn>>,
}

impl PendingQueues {
    pub(crate) fn push(&mut self, endpoint: u8, request: PendingIn) {
        self.queues.entry(endpoint).or_default().push_back(request);
    }

    pub(crate) fn front(&self, endpoint: u8) -> Option<PendingIn> {
        self.queues
            .get(&endpoint)
            .and_then(|queue| queue.front().copied())
    }

    pub(crate) fn pop_front(&mut self, endpoint: u8) -> Option<PendingIn> {
        self.queues.get_mut(&endpoint).and_then(VecDeque::pop_front)
    }

    /// Removes the request with `seqnum` wherever it waits; false when none does.
    pub(crate) fn remove(&mut self, seqnum: u32) -> bool {
        for queue in self.queues.values_mut() {
            if let Some(position) = queue.iter().position(|request| request.seqnum == seqnum) {
                queue.remove(position);
                return true;
            }
        }
        false
    }

    /// Endpoints with at least one queued request.
    pub(crate) fn endpoints(&self) -> Vec<u8> {
        self.queues
            .iter()
            .filter(|(_, queue)| !queue.is_empty())
            .map(|(&endpoint, _)| endpoint)
            .collect()
    }

    /// Queued requests over all endpoints.
    pub(crate) fn len(&self) -> usize {
        self.queues.values().map(VecDeque::len).sum()
    }
}
