//! Dense numbering of the states met while exploring a product (GMC,
//! certification MDP, automaton constructions): the map from a key to its
//! index and the keys by index, in order of first appearance.

use std::collections::hash_map::Entry;
use std::hash::Hash;

use rustc_hash::FxHashMap;

/// The keys seen so far, numbered `0, 1, ...` in order of first appearance.
#[derive(Debug, Clone)]
pub(crate) struct Interner<K> {
    ids: FxHashMap<K, u32>,
    keys: Vec<K>,
}

/// A new key would need an index beyond `u32::MAX`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct TooManyKeys;

impl<K> Default for Interner<K> {
    fn default() -> Self {
        Self {
            ids: FxHashMap::default(),
            keys: Vec::new(),
        }
    }
}

impl<K: Hash + Eq + Clone> Interner<K> {
    /// The index of `key`, numbering it next if it is new.
    pub(crate) fn intern(&mut self, key: K) -> Result<u32, TooManyKeys> {
        match self.ids.entry(key) {
            Entry::Occupied(entry) => Ok(*entry.get()),
            Entry::Vacant(entry) => {
                let id = u32::try_from(self.keys.len()).map_err(|_| TooManyKeys)?;
                self.keys.push(entry.key().clone());
                entry.insert(id);
                Ok(id)
            }
        }
    }

    /// The index of `key`, if it has been numbered.
    pub(crate) fn get(&self, key: &K) -> Option<u32> {
        self.ids.get(key).copied()
    }
}

impl<K> Interner<K> {
    /// The number of keys.
    pub(crate) fn len(&self) -> usize {
        self.keys.len()
    }

    /// The keys by index.
    pub(crate) fn keys(&self) -> &[K] {
        &self.keys
    }

    /// The keys by index, without the map.
    pub(crate) fn into_keys(self) -> Vec<K> {
        self.keys
    }

    /// The keys in index order.
    pub(crate) fn iter(&self) -> std::slice::Iter<'_, K> {
        self.keys.iter()
    }
}

impl<K> std::ops::Index<usize> for Interner<K> {
    type Output = K;

    /// The key numbered `index`.
    fn index(&self, index: usize) -> &K {
        &self.keys[index]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_numbered_in_order_of_first_appearance() {
        let mut interner = Interner::default();
        let ids: Vec<u32> = ["b", "a", "b", "c", "a"]
            .into_iter()
            .map(|key| interner.intern(key).unwrap())
            .collect();
        assert_eq!(ids, [0, 1, 0, 2, 1]);
        assert_eq!(interner.keys(), ["b", "a", "c"]);
        assert_eq!(interner.get(&"c"), Some(2));
        assert_eq!(interner.get(&"d"), None);
        assert_eq!(interner.len(), 3);
    }
}
