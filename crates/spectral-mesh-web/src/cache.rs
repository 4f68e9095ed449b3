//! A cache bounded in bytes: least recently used entries go first.

use std::collections::HashMap;
use std::hash::Hash;
use std::sync::{Arc, Mutex};

struct Slot<V> {
    value: Arc<V>,
    bytes: usize,
    last_used: u64,
}

struct Inner<K, V> {
    map: HashMap<K, Slot<V>>,
    clock: u64,
    used: usize,
}

/// A thread-safe map from `K` to shared `V`, holding at most `cap` bytes (as estimated by
/// the caller on insert). Inserting past the cap evicts the least recently used entries;
/// an entry larger than the cap is refused.
pub struct ByteLru<K, V> {
    inner: Mutex<Inner<K, V>>,
    cap: usize,
}

impl<K: Eq + Hash + Clone, V> ByteLru<K, V> {
    /// An empty cache of `cap` bytes.
    pub fn new(cap: usize) -> Self {
        Self {
            inner: Mutex::new(Inner {
                map: HashMap::new(),
                clock: 0,
                used: 0,
            }),
            cap,
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Inner<K, V>> {
        // A poisoned lock only means another request panicked mid-update of counters;
        // the map itself stays consistent, so keep serving.
        self.inner
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The capacity in bytes.
    pub fn capacity(&self) -> usize {
        self.cap
    }

    /// Bytes in use.
    pub fn used(&self) -> usize {
        self.lock().used
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.lock().map.len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The value for `key`, marking it as most recently used.
    pub fn get(&self, key: &K) -> Option<Arc<V>> {
        let mut g = self.lock();
        g.clock += 1;
        let now = g.clock;
        g.map.get_mut(key).map(|s| {
            s.last_used = now;
            s.value.clone()
        })
    }

    /// The first entry (most recently used first) whose key satisfies `pred`.
    pub fn find(&self, pred: impl Fn(&K) -> bool) -> Option<(K, Arc<V>)> {
        let mut g = self.lock();
        g.clock += 1;
        let now = g.clock;
        let key = g
            .map
            .iter()
            .filter(|(k, _)| pred(k))
            .max_by_key(|(_, s)| s.last_used)
            .map(|(k, _)| k.clone())?;
        let s = g.map.get_mut(&key)?;
        s.last_used = now;
        Some((key, s.value.clone()))
    }

    /// All keys satisfying `pred`.
    pub fn keys(&self, pred: impl Fn(&K) -> bool) -> Vec<K> {
        self.lock()
            .map
            .keys()
            .filter(|k| pred(k))
            .cloned()
            .collect()
    }

    /// Inserts `value` of `bytes` bytes, evicting least recently used entries to make room.
    /// Returns false (and stores nothing) when `bytes` exceeds the capacity.
    pub fn insert(&self, key: K, value: Arc<V>, bytes: usize) -> bool {
        if bytes > self.cap {
            return false;
        }
        let mut g = self.lock();
        if let Some(old) = g.map.remove(&key) {
            g.used -= old.bytes;
        }
        while g.used + bytes > self.cap {
            let Some(victim) = g
                .map
                .iter()
                .min_by_key(|(_, s)| s.last_used)
                .map(|(k, _)| k.clone())
            else {
                break;
            };
            if let Some(s) = g.map.remove(&victim) {
                g.used -= s.bytes;
            }
        }
        g.clock += 1;
        let now = g.clock;
        g.used += bytes;
        g.map.insert(
            key,
            Slot {
                value,
                bytes,
                last_used: now,
            },
        );
        true
    }

    /// Removes every entry whose key satisfies `pred`.
    pub fn remove_where(&self, pred: impl Fn(&K) -> bool) {
        let mut g = self.lock();
        let keys: Vec<K> = g.map.keys().filter(|k| pred(k)).cloned().collect();
        for k in keys {
            if let Some(s) = g.map.remove(&k) {
                g.used -= s.bytes;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evicts_least_recently_used_within_cap() {
        let c: ByteLru<u32, u32> = ByteLru::new(100);
        assert!(c.insert(1, Arc::new(1), 40));
        assert!(c.insert(2, Arc::new(2), 40));
        assert!(c.get(&1).is_some()); // 2 is now the oldest
        assert!(c.insert(3, Arc::new(3), 40));
        assert!(c.get(&2).is_none());
        assert!(c.get(&1).is_some() && c.get(&3).is_some());
        assert_eq!(c.used(), 80);
        assert!(!c.insert(4, Arc::new(4), 101));
        assert_eq!(c.len(), 2);
        c.remove_where(|&k| k == 1);
        assert_eq!(c.used(), 40);
    }
}
