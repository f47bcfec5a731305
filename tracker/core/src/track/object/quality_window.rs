//! The recent quality of one object: a fixed window of per-tick quality scores and their mean.

/// The last `capacity` quality scores (each in [0, 1]) of one object. Allocates once, at construction.
#[derive(Debug)]
pub(crate) struct QualityWindow {
    scores: Vec<f32>,
    capacity: usize,
    next: usize,
    sum: f64,
}

impl Clone for QualityWindow {
    fn clone(&self) -> Self {
        Self {
            scores: self.scores.clone(),
            capacity: self.capacity,
            next: self.next,
            sum: self.sum,
        }
    }

    /// Reuses this window's buffer (no allocation once it holds `capacity` scores).
    fn clone_from(&mut self, source: &Self) {
        self.scores.clone_from(&source.scores);
        self.capacity = source.capacity;
        self.next = source.next;
        self.sum = source.sum;
    }
}

impl QualityWindow {
    /// An empty window of `capacity` ticks (0: the window is never full).
    pub fn new(capacity: usize) -> Self {
        Self {
            scores: Vec::with_capacity(capacity),
            capacity,
            next: 0,
            sum: 0.0,
        }
    }

    /// Records one tick's score, dropping the oldest once the window is full.
    pub fn push(&mut self, score: f32) {
        if self.capacity == 0 {
            return;
        }
        if self.scores.len() < self.capacity {
            self.scores.push(score);
        } else {
            self.sum -= f64::from(self.scores[self.next]);
            self.scores[self.next] = score;
        }
        self.sum += f64::from(score);
        self.next = (self.next + 1) % self.capacity;
    }

    /// The mean score over the window once it holds `capacity` ticks; `None` before.
    pub fn full_mean(&self) -> Option<f64> {
        (self.capacity > 0 && self.scores.len() == self.capacity)
            .then(|| self.sum / self.capacity as f64)
    }

    /// Forgets every score (the object moved to a new place).
    pub fn clear(&mut self) {
        self.scores.clear();
        self.next = 0;
        self.sum = 0.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_is_over_the_last_capacity_scores_and_only_when_full() {
        let mut w = QualityWindow::new(3);
        w.push(1.0);
        w.push(0.5);
        assert_eq!(w.full_mean(), None);
        w.push(0.0);
        assert!((w.full_mean().unwrap() - 0.5).abs() < 1e-9);
        // 0.5, 0.0, 0.1: the first 1.0 has left the window.
        w.push(0.1);
        assert!((w.full_mean().unwrap() - 0.2).abs() < 1e-6);
        for _ in 0..1000 {
            w.push(0.3);
        }
        assert!((w.full_mean().unwrap() - 0.3).abs() < 1e-6);
        w.clear();
        assert_eq!(w.full_mean(), None);
        assert_eq!(QualityWindow::new(0).full_mean(), None);
    }
}
