//! Wall time of the named steps of one phase of a run (the load's: read,
//! frame, compile; the build's: boxes, clusters, PLOC, collapse, leaves),
//! kept in order as plain data for `--stats`. A fixed list, so the
//! timings that carry it stay `Copy` and a step costs no allocation.

use serde::ser::{Serialize, SerializeMap, Serializer};
use std::time::{Duration, Instant};

/// Most steps one list holds; a step past them is added to the last.
const MAX_STEPS: usize = 12;

/// Named steps in the order they first ran, each with its wall time.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Steps {
    names: [&'static str; MAX_STEPS],
    seconds: [f64; MAX_STEPS],
    len: usize,
}

impl Steps {
    /// Adds `time` to step `name` (a new step at the end if it has not run).
    pub fn add(&mut self, name: &'static str, time: Duration) {
        let k = match self.names[..self.len].iter().position(|&n| n == name) {
            Some(k) => k,
            None if self.len < MAX_STEPS => {
                self.names[self.len] = name;
                self.len += 1;
                self.len - 1
            }
            None => MAX_STEPS - 1,
        };
        self.seconds[k] += time.as_secs_f64();
    }

    /// Runs `work` as step `name`.
    pub fn time<T>(&mut self, name: &'static str, work: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = work();
        self.add(name, start.elapsed());
        out
    }

    /// Every step of `other` after (or added to) these.
    pub fn extend(&mut self, other: &Steps) {
        for (name, s) in other.iter() {
            self.add(name, Duration::from_secs_f64(s));
        }
    }

    /// The steps in order, with their seconds.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, f64)> + '_ {
        (0..self.len).map(|k| (self.names[k], self.seconds[k]))
    }

    /// All the steps' seconds together.
    pub fn total_s(&self) -> f64 {
        self.seconds[..self.len].iter().sum()
    }
}

/// A map from step name to seconds, in order.
impl Serialize for Steps {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.len))?;
        for (name, s) in self.iter() {
            map.serialize_entry(name, &s)?;
        }
        map.end()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_keep_their_order_and_add_up_by_name() {
        let mut s = Steps::default();
        s.add("read", Duration::from_millis(250));
        s.add("frame", Duration::from_millis(500));
        s.add("read", Duration::from_millis(125));
        let got: Vec<_> = s.iter().collect();
        assert_eq!(got, vec![("read", 0.375), ("frame", 0.5)]);
        assert_eq!(s.total_s(), 0.875);
        let json = serde_json::to_string(&s).unwrap();
        assert_eq!(json, r#"{"read":0.375,"frame":0.5}"#);
        // Past the fixed list, a step's time still counts, on the last.
        let mut full = Steps::default();
        let names = [
            "a", "b", "c", "d", "e", "f", "g", "h", "i", "j", "k", "l", "m",
        ];
        for name in names {
            full.add(name, Duration::from_secs(1));
        }
        assert_eq!(full.iter().count(), MAX_STEPS);
        assert_eq!(full.total_s(), names.len() as f64);
    }
}
