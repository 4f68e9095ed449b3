//! The server's memory: a cache bounded in bytes (least recently used entries go first)
//! and the reservations of work in progress, under one budget.
//!
//! Two figures bound what the server holds:
//! - the cache's capacity (`--cache-mib`): meshes and analyses kept between requests;
//! - the budget (`--memory-mib`): the cache plus every reservation (eigenbasis jobs at
//!   their estimated peak, uploads being read and parsed, field requests being computed).
//!
//! Making room evicts the least recently used entries that nothing else is using (a
//! value whose `Arc` is held by a request or a job is skipped: dropping the cache's copy
//! would free nothing). Entries nobody asked for during the idle time are dropped by
//! [`ByteLru::expire`].

use std::collections::HashMap;
use std::hash::Hash;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// What the cache needs to know of a value stored under keys of type `K`.
pub trait Entry<K> {
    /// True while something besides the cache holds the value (evicting it would free
    /// nothing): a request or a job using it.
    fn in_use(self: &Arc<Self>) -> bool;
    /// Of `keys`, those of the entries that go with this one when it is evicted (an
    /// evicted mesh takes its analyses along); it is only evictable when they all are.
    fn dependents(&self, keys: &[K]) -> Vec<K> {
        let _ = keys;
        Vec::new()
    }
}

struct Slot<V> {
    value: Arc<V>,
    bytes: usize,
    last_used: u64,
    touched: Instant,
}

struct Inner<K, V> {
    map: HashMap<K, Slot<V>>,
    clock: u64,
    used: usize,
    reserved: usize,
}

/// Why room could not be made.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Shortfall {
    /// Bytes asked for.
    pub wanted: usize,
    /// Bytes the cache holds that could not be evicted (in use).
    pub pinned: usize,
    /// Bytes the cache holds in all.
    pub cached: usize,
    /// Bytes reserved by work in progress.
    pub reserved: usize,
    /// The bound that was hit (the budget or the cache's capacity).
    pub limit: usize,
}

impl Shortfall {
    /// True when the request could never fit, whatever finishes first.
    pub fn never_fits(&self) -> bool {
        self.wanted > self.limit
    }
}

/// A thread-safe map from `K` to shared `V`, holding at most `cap` bytes (as estimated by
/// the caller on insert), with reservations against a total `budget`.
pub struct ByteLru<K, V> {
    inner: Mutex<Inner<K, V>>,
    cap: usize,
    budget: usize,
    /// Signalled whenever bytes are freed (a reservation released, an entry removed).
    freed: tokio::sync::Notify,
}

/// Bytes reserved from a [`ByteLru`]'s budget; released when dropped.
pub struct Reservation<K, V> {
    owner: Arc<ByteLru<K, V>>,
    bytes: usize,
}

impl<K, V> Reservation<K, V> {
    /// Bytes reserved.
    pub fn bytes(&self) -> usize {
        self.bytes
    }
}

impl<K, V> std::fmt::Debug for Reservation<K, V> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Reservation({} bytes)", self.bytes)
    }
}

impl<K, V> Drop for Reservation<K, V> {
    fn drop(&mut self) {
        {
            let mut g = self.owner.inner.lock().unwrap_or_else(|p| p.into_inner());
            g.reserved = g.reserved.saturating_sub(self.bytes);
        }
        self.owner.freed.notify_waiters();
    }
}

impl<K: Eq + Hash + Clone, V: Entry<K>> ByteLru<K, V> {
    /// An empty cache of `cap` bytes within a total of `budget` bytes (`cap <= budget`
    /// is enforced by lowering `cap`).
    pub fn new(cap: usize, budget: usize) -> Self {
        Self {
            inner: Mutex::new(Inner {
                map: HashMap::new(),
                clock: 0,
                used: 0,
                reserved: 0,
            }),
            cap: cap.min(budget),
            budget,
            freed: tokio::sync::Notify::new(),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Inner<K, V>> {
        // A poisoned lock only means another request panicked mid-update of counters;
        // the map itself stays consistent, so keep serving.
        self.inner
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The capacity of the cache in bytes.
    pub fn capacity(&self) -> usize {
        self.cap
    }

    /// The total budget in bytes (cache and reservations).
    pub fn budget(&self) -> usize {
        self.budget
    }

    /// Bytes the cache holds.
    pub fn used(&self) -> usize {
        self.lock().used
    }

    /// Bytes reserved by work in progress.
    pub fn reserved(&self) -> usize {
        self.lock().reserved
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
            s.touched = Instant::now();
            s.value.clone()
        })
    }

    /// The value for `key` without marking it as used.
    pub fn peek(&self, key: &K) -> Option<Arc<V>> {
        self.lock().map.get(key).map(|s| s.value.clone())
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

    /// Evicts least recently used entries (with their dependents; entries in use are
    /// skipped) until `fits(used, reserved)` holds or nothing more can go. Returns true
    /// when it holds. Evicted values are pushed to `dropped`, to be dropped after the
    /// lock is released.
    fn make_room(
        g: &mut Inner<K, V>,
        fits: impl Fn(usize, usize) -> bool,
        protect: Option<&K>,
        dropped: &mut Vec<Arc<V>>,
    ) -> bool {
        if fits(g.used, g.reserved) {
            return true;
        }
        let mut order: Vec<(u64, K)> = g
            .map
            .iter()
            .filter(|(k, _)| Some(*k) != protect)
            .map(|(k, s)| (s.last_used, k.clone()))
            .collect();
        order.sort_by_key(|(t, _)| *t);
        let all: Vec<K> = g.map.keys().cloned().collect();
        for (_, key) in order {
            let Some(slot) = g.map.get(&key) else {
                continue;
            };
            let deps = slot.value.dependents(&all);
            let mut group = vec![key.clone()];
            group.extend(deps.into_iter().filter(|d| *d != key));
            let evictable = group
                .iter()
                .all(|k| Some(k) != protect && g.map.get(k).is_none_or(|s| !s.value.in_use()));
            if !evictable {
                continue;
            }
            for k in group {
                if let Some(s) = g.map.remove(&k) {
                    g.used -= s.bytes;
                    dropped.push(s.value);
                }
            }
            if fits(g.used, g.reserved) {
                return true;
            }
        }
        fits(g.used, g.reserved)
    }

    fn shortfall(g: &Inner<K, V>, wanted: usize, limit: usize) -> Shortfall {
        let pinned = g
            .map
            .values()
            .filter(|s| s.value.in_use())
            .map(|s| s.bytes)
            .sum();
        Shortfall {
            wanted,
            pinned,
            cached: g.used,
            reserved: g.reserved,
            limit,
        }
    }

    /// Inserts `value` of `bytes` bytes (replacing the entry of `key`, if any), evicting
    /// least recently used entries to stay within the capacity and the budget. When that
    /// is not possible, nothing is stored and the shortfall is returned.
    pub fn insert(&self, key: K, value: Arc<V>, bytes: usize) -> Result<(), Shortfall> {
        let mut dropped = Vec::new();
        let result = {
            let mut g = self.lock();
            let old = g.map.get(&key).map_or(0, |s| s.bytes);
            let (cap, budget) = (self.cap, self.budget);
            let fits = |used: usize, reserved: usize| {
                let used = used - old.min(used) + bytes;
                used <= cap && used + reserved <= budget
            };
            if bytes > cap {
                Err(Self::shortfall(&g, bytes, cap))
            } else if Self::make_room(&mut g, fits, Some(&key), &mut dropped) {
                if let Some(s) = g.map.remove(&key) {
                    g.used -= s.bytes;
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
                        touched: Instant::now(),
                    },
                );
                Ok(())
            } else {
                let limit = if g.used + bytes > cap { cap } else { budget };
                Err(Self::shortfall(&g, bytes, limit))
            }
        };
        let freed = !dropped.is_empty();
        drop(dropped);
        if freed {
            self.freed.notify_waiters();
        }
        result
    }

    /// Updates the size of the entry of `key` (if still there) to `bytes`, evicting
    /// others to stay within bounds; the entry itself stays even when that is not
    /// possible (the memory is already in use: the next reservations wait for it).
    pub fn resize(&self, key: &K, bytes: usize) {
        let mut dropped = Vec::new();
        {
            let mut g = self.lock();
            let Some(old) = g.map.get(key).map(|s| s.bytes) else {
                return;
            };
            g.used = g.used - old + bytes;
            if let Some(s) = g.map.get_mut(key) {
                s.bytes = bytes;
            }
            let (cap, budget) = (self.cap, self.budget);
            Self::make_room(
                &mut g,
                |used, reserved| used <= cap && used + reserved <= budget,
                Some(key),
                &mut dropped,
            );
        }
        if !dropped.is_empty() {
            drop(dropped);
            self.freed.notify_waiters();
        }
    }

    /// Reserves `bytes` of the budget now, evicting cached entries to make room, or
    /// returns the shortfall.
    pub fn try_reserve(self: &Arc<Self>, bytes: usize) -> Result<Reservation<K, V>, Shortfall> {
        let mut dropped = Vec::new();
        let result = {
            let mut g = self.lock();
            let budget = self.budget;
            if bytes > budget {
                Err(Self::shortfall(&g, bytes, budget))
            } else if Self::make_room(
                &mut g,
                |used, reserved| used + reserved + bytes <= budget,
                None,
                &mut dropped,
            ) {
                g.reserved += bytes;
                Ok(Reservation {
                    owner: self.clone(),
                    bytes,
                })
            } else {
                Err(Self::shortfall(&g, bytes, budget))
            }
        };
        if !dropped.is_empty() {
            drop(dropped);
            self.freed.notify_waiters();
        }
        result
    }

    /// [`ByteLru::try_reserve`], waiting until `deadline` for other work to free memory.
    pub async fn reserve(
        self: &Arc<Self>,
        bytes: usize,
        deadline: tokio::time::Instant,
    ) -> Result<Reservation<K, V>, Shortfall> {
        loop {
            let notified = self.freed.notified();
            tokio::pin!(notified);
            notified.as_mut().enable();
            match self.try_reserve(bytes) {
                Ok(r) => return Ok(r),
                Err(s) if s.never_fits() => return Err(s),
                Err(s) => {
                    // Wake at least once a second: an entry stops being in use without
                    // a notification (a request dropping its `Arc`).
                    let wake = deadline.min(tokio::time::Instant::now() + Duration::from_secs(1));
                    if tokio::time::timeout_at(wake, notified).await.is_err()
                        && tokio::time::Instant::now() >= deadline
                    {
                        return Err(s);
                    }
                }
            }
        }
    }

    /// Removes every entry whose key satisfies `pred`.
    pub fn remove_where(&self, pred: impl Fn(&K) -> bool) {
        let mut dropped = Vec::new();
        {
            let mut g = self.lock();
            let keys: Vec<K> = g.map.keys().filter(|k| pred(k)).cloned().collect();
            for k in keys {
                if let Some(s) = g.map.remove(&k) {
                    g.used -= s.bytes;
                    dropped.push(s.value);
                }
            }
        }
        if !dropped.is_empty() {
            drop(dropped);
            self.freed.notify_waiters();
        }
    }

    /// Drops the entries (with their dependents) nobody asked for during `idle`, unless
    /// in use. Returns how many went.
    pub fn expire(&self, idle: Duration) -> usize {
        let mut dropped = Vec::new();
        {
            let mut g = self.lock();
            let now = Instant::now();
            let all: Vec<K> = g.map.keys().cloned().collect();
            let stale: Vec<K> = g
                .map
                .iter()
                .filter(|(_, s)| now.duration_since(s.touched) >= idle)
                .map(|(k, _)| k.clone())
                .collect();
            for key in stale {
                let Some(slot) = g.map.get(&key) else {
                    continue;
                };
                let mut group = vec![key.clone()];
                group.extend(slot.value.dependents(&all));
                let evictable = group.iter().all(|k| {
                    g.map
                        .get(k)
                        .is_none_or(|s| !s.value.in_use() && now.duration_since(s.touched) >= idle)
                });
                if evictable {
                    for k in group {
                        if let Some(s) = g.map.remove(&k) {
                            g.used -= s.bytes;
                            dropped.push(s.value);
                        }
                    }
                }
            }
        }
        let n = dropped.len();
        if n > 0 {
            drop(dropped);
            self.freed.notify_waiters();
        }
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A value that is in use while a clone of its `Arc` is held; the entry of key `x`
    /// takes the entries of keys `1000 * x..1000 * (x + 1)` along when it goes.
    struct V(u32);
    impl Entry<u32> for V {
        fn in_use(self: &Arc<Self>) -> bool {
            Arc::strong_count(self) > 1
        }
        fn dependents(&self, keys: &[u32]) -> Vec<u32> {
            let x = self.0;
            keys.iter()
                .copied()
                .filter(|k| (1000 * x..1000 * (x + 1)).contains(k))
                .collect()
        }
    }

    fn v(x: u32) -> Arc<V> {
        Arc::new(V(x))
    }

    #[test]
    fn evicts_least_recently_used_within_cap() {
        let c: ByteLru<u32, V> = ByteLru::new(100, 1000);
        assert!(c.insert(1, v(1), 40).is_ok());
        assert!(c.insert(2, v(2), 40).is_ok());
        assert!(c.get(&1).is_some()); // 2 is now the oldest
        assert!(c.insert(3, v(3), 40).is_ok());
        assert!(c.get(&2).is_none());
        assert!(c.get(&1).is_some() && c.get(&3).is_some());
        assert_eq!(c.used(), 80);
        let e = c.insert(4, v(4), 101).unwrap_err();
        assert!(e.never_fits());
        assert_eq!(c.len(), 2);
        c.remove_where(|&k| k == 1);
        assert_eq!(c.used(), 40);
        assert_eq!(c.get(&3).map(|x| x.0), Some(3));
    }

    #[test]
    fn entries_in_use_stay_and_reservations_count() {
        let c: Arc<ByteLru<u32, V>> = Arc::new(ByteLru::new(100, 150));
        c.insert(1, v(1), 60).unwrap();
        c.insert(2, v(2), 30).unwrap();
        let held = c.get(&1).unwrap(); // in use: cannot be evicted
        // 60 + 30 cached; 70 more needs 10 freed: entry 2 goes, entry 1 stays.
        let r = c.try_reserve(70).unwrap();
        assert_eq!((c.used(), c.reserved(), c.len()), (60, 70, 1));
        // 60 pinned + 70 reserved + 30 > 150 and nothing can go.
        let s = c.try_reserve(30).unwrap_err();
        assert!(!s.never_fits());
        assert_eq!((s.pinned, s.reserved), (60, 70));
        assert!(c.insert(3, v(3), 30).is_err());
        drop(r);
        assert_eq!(c.reserved(), 0);
        c.insert(3, v(3), 30).unwrap();
        drop(held);
        // Not in use any more: a reservation may evict it.
        let _r = c.try_reserve(120).unwrap();
        assert!(c.peek(&1).is_none());
        assert!(c.try_reserve(151).unwrap_err().never_fits());
    }

    #[test]
    fn resize_and_expire() {
        let c: ByteLru<u32, V> = ByteLru::new(100, 100);
        c.insert(1, v(1), 10).unwrap();
        c.insert(2, v(2), 10).unwrap();
        c.resize(&2, 95); // entry 1 goes to make room
        assert_eq!((c.used(), c.len()), (95, 1));
        std::thread::sleep(Duration::from_millis(20));
        let held = c.get(&2).unwrap();
        assert_eq!(c.expire(Duration::from_millis(1)), 0, "in use");
        drop(held);
        assert_eq!(c.expire(Duration::from_secs(60)), 0, "used recently");
        std::thread::sleep(Duration::from_millis(5));
        assert_eq!(c.expire(Duration::from_millis(1)), 1);
        assert!(c.is_empty());
    }

    #[test]
    fn dependents_go_along_and_pin_their_owner() {
        let c: Arc<ByteLru<u32, V>> = Arc::new(ByteLru::new(100, 100));
        c.insert(1, v(1), 10).unwrap();
        c.insert(1000, v(1000), 20).unwrap();
        c.insert(1001, v(1001), 20).unwrap();
        c.insert(2, v(2), 10).unwrap();
        let dep = c.get(&1001).unwrap();
        // Entry 1 is the oldest but its dependent 1001 is in use: 1000 and 2 go.
        let _r = c.try_reserve(70).unwrap();
        assert!(c.peek(&1).is_some() && c.peek(&1001).is_some());
        assert!(c.peek(&1000).is_none() && c.peek(&2).is_none());
        drop(dep);
        // Now 1 can go, and 1001 with it.
        let _r2 = c.try_reserve(30).unwrap();
        assert!(c.is_empty());
    }

    #[tokio::test]
    async fn reserve_waits_for_a_release() {
        let c: Arc<ByteLru<u32, V>> = Arc::new(ByteLru::new(100, 100));
        let r = c.try_reserve(80).unwrap();
        let c2 = c.clone();
        let waiter = tokio::spawn(async move {
            let deadline = tokio::time::Instant::now() + Duration::from_secs(10);
            c2.reserve(50, deadline).await.map(|r| r.bytes())
        });
        tokio::time::sleep(Duration::from_millis(50)).await;
        drop(r);
        assert_eq!(waiter.await.unwrap(), Ok(50));
        // A deadline that passes: the shortfall.
        let _r = c.try_reserve(80).unwrap();
        let deadline = tokio::time::Instant::now() + Duration::from_millis(100);
        assert!(c.reserve(50, deadline).await.is_err());
    }
}
