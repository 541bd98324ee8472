//! Dense lists of merges with a copy of their nodes (one cache line apiece),
//! so that a frame tests them all in one vector loop (§5.1). Where each merge
//! sits in a list is kept by the caller, beside the merge's other run-time
//! state, so that a walk over dependencies touches one record per merge.

use super::{NONE, Node};

/// Which list a merge can be in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum List {
    /// Merges not in place whose requirements all are: may merge next.
    Mergeable,
    /// The nodes of the display vertices that have one.
    Active,
}

/// Per merge, what the run time knows of it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct MergeState {
    pub(crate) merged: bool,
    /// How many of its requirements are not in place.
    pub(crate) missing: u32,
    /// Its place in each [`List`] ([`NONE`]: not in it).
    at: [u32; 2],
}

impl MergeState {
    pub(crate) const NEW: MergeState = MergeState {
        merged: false,
        missing: 0,
        at: [NONE; 2],
    };
}

/// `ids[i]` is a merge, `nodes[i]` a copy of its node.
#[derive(Debug, Clone, Default)]
pub(crate) struct NodeList {
    pub(crate) ids: Vec<u32>,
    pub(crate) nodes: Vec<Node>,
}

impl NodeList {
    pub(crate) fn with_capacity(n: usize) -> Self {
        Self {
            ids: Vec::with_capacity(n),
            nodes: Vec::with_capacity(n),
        }
    }

    pub(crate) fn clear(&mut self) {
        self.ids.clear();
        self.nodes.clear();
    }

    pub(crate) fn len(&self) -> usize {
        self.ids.len()
    }

    /// Adds merge `k` to list `which` unless it is there.
    pub(crate) fn insert(&mut self, which: List, k: u32, node: &Node, state: &mut [MergeState]) {
        let at = &mut state[k as usize].at[which as usize];
        if *at == NONE {
            *at = self.ids.len() as u32;
            self.ids.push(k);
            self.nodes.push(*node);
        }
    }

    /// Takes merge `k` out of list `which` if it is there.
    pub(crate) fn remove(&mut self, which: List, k: u32, state: &mut [MergeState]) {
        let at = std::mem::replace(&mut state[k as usize].at[which as usize], NONE);
        if at == NONE {
            return;
        }
        self.ids.swap_remove(at as usize);
        self.nodes.swap_remove(at as usize);
        if let Some(&moved) = self.ids.get(at as usize) {
            state[moved as usize].at[which as usize] = at;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mergetree::NormalCone;
    use glam::Vec3;

    /// The copies follow the ids through inserts and swap-removes, and each
    /// merge's recorded place stays right.
    #[test]
    fn node_list_keeps_each_node_beside_its_id() {
        let nodes: Vec<Node> = (0..10)
            .map(|i| Node {
                center: Vec3::splat(i as f32),
                radius: i as f32,
                downswitch: 0.0,
                upswitch: 0.0,
                cone: NormalCone::EMPTY,
            })
            .collect();
        let mut state = vec![MergeState::NEW; 10];
        let mut list = NodeList::with_capacity(10);
        let which = List::Active;
        for k in [3, 7, 1, 9, 3] {
            list.insert(which, k, &nodes[k as usize], &mut state);
        }
        for k in [7, 5, 3] {
            list.remove(which, k, &mut state);
        }
        list.insert(which, 0, &nodes[0], &mut state);
        let mut ids = list.ids.clone();
        ids.sort_unstable();
        assert_eq!(ids, [0, 1, 9]);
        assert_eq!(list.len(), 3);
        for (i, (k, n)) in list.ids.iter().zip(&list.nodes).enumerate() {
            assert_eq!(n.radius, *k as f32);
            assert_eq!(state[*k as usize].at[which as usize], i as u32);
            assert_eq!(state[*k as usize].at[List::Mergeable as usize], NONE);
        }
        assert_eq!(state[7].at[which as usize], NONE);
    }
}
