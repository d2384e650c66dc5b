//! A small reusable graph toolkit: adjacency lists in compressed (CSR) form,
//! breadth- and depth-first orders, connected components and union-find.
//!
//! The reverse-subdivision algorithms build such graphs over faces or vertices (for
//! example the face graph of reverse Doo-Sabin and its candidate graph), so everything
//! here works on plain `u32` node indices and runs in time linear in nodes plus edges.

/// An undirected graph on nodes `0..n` stored as compressed adjacency lists.
///
/// ```
/// use mesh_topo::graph::Graph;
/// let g = Graph::from_edges(5, &[(0, 1), (1, 2), (3, 4)]);
/// assert_eq!((g.node_count(), g.edge_count()), (5, 3));
/// assert_eq!(g.neighbors(1), &[0, 2]);
/// let (labels, count) = g.connected_components();
/// assert_eq!(count, 2);
/// assert_eq!(labels, vec![0, 0, 0, 1, 1]);
/// assert_eq!(g.bfs_order(0), vec![0, 1, 2]);
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Graph {
    offsets: Vec<u32>,
    targets: Vec<u32>,
}

impl Graph {
    /// Builds the graph from undirected edges. Each edge is stored in both directions;
    /// a node's neighbours keep the order in which its edges were given.
    ///
    /// ```
    /// use mesh_topo::graph::Graph;
    ///
    /// let g = Graph::from_edges(4, &[(0, 1), (2, 0), (1, 2)]);
    /// assert_eq!((g.node_count(), g.edge_count()), (4, 3));
    /// assert_eq!(g.neighbors(0), &[1, 2]); // in the order the edges were given
    /// assert_eq!(g.neighbors(2), &[0, 1]);
    /// assert!(g.neighbors(3).is_empty());
    /// ```
    ///
    /// # Panics
    /// If an edge names a node `>= node_count` (the caller builds edges from its own
    /// indices, so this is a programming error, not bad user data), or if `node_count`
    /// or twice the edge count exceeds `u32::MAX` (nodes and offsets are `u32`).
    pub fn from_edges(node_count: usize, edges: &[(u32, u32)]) -> Self {
        assert!(node_count <= u32::MAX as usize, "graph of {node_count} nodes: at most u32::MAX");
        assert!(edges.len() <= u32::MAX as usize / 2, "graph of {} edges: at most u32::MAX / 2", edges.len());
        let mut offsets = vec![0u32; node_count + 1];
        for &(a, b) in edges {
            assert!((a as usize) < node_count && (b as usize) < node_count, "graph edge out of range");
            offsets[a as usize + 1] += 1;
            offsets[b as usize + 1] += 1;
        }
        for i in 0..node_count {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut targets = vec![0u32; offsets[node_count] as usize];
        for &(a, b) in edges {
            targets[fill[a as usize] as usize] = b;
            fill[a as usize] += 1;
            targets[fill[b as usize] as usize] = a;
            fill[b as usize] += 1;
        }
        Self { offsets, targets }
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Number of undirected edges.
    pub fn edge_count(&self) -> usize {
        self.targets.len() / 2
    }

    /// Neighbours of `node`, in insertion order.
    ///
    /// # Panics
    /// If `node >= self.node_count()` (a programming error, as in [`Graph::from_edges`]).
    pub fn neighbors(&self, node: u32) -> &[u32] {
        &self.targets[self.offsets[node as usize] as usize..self.offsets[node as usize + 1] as usize]
    }

    /// Nodes reachable from `start` in breadth-first order.
    ///
    /// ```
    /// use mesh_topo::graph::Graph;
    ///
    /// // A tree 0 - {1, 2}, 1 - 3, 2 - 4, and node 5 on its own.
    /// let g = Graph::from_edges(6, &[(0, 1), (0, 2), (1, 3), (2, 4)]);
    /// assert_eq!(g.bfs_order(0), [0, 1, 2, 3, 4]);
    /// assert_eq!(g.bfs_order(3), [3, 1, 0, 2, 4]);
    /// assert_eq!(g.bfs_order(5), [5]);
    /// ```
    ///
    /// # Panics
    /// If `start >= self.node_count()`.
    pub fn bfs_order(&self, start: u32) -> Vec<u32> {
        let mut visited = vec![false; self.node_count()];
        let mut order = Vec::new();
        self.bfs_into(start, &mut visited, &mut order);
        order
    }

    /// Nodes reachable from `start` in depth-first (preorder) order, neighbours visited
    /// in insertion order.
    ///
    /// ```
    /// use mesh_topo::graph::Graph;
    ///
    /// // A tree 0 - {1, 2}, 1 - 3, 2 - 4, and node 5 on its own.
    /// let g = Graph::from_edges(6, &[(0, 1), (0, 2), (1, 3), (2, 4)]);
    /// assert_eq!(g.dfs_order(0), [0, 1, 3, 2, 4]); // breadth-first: [0, 1, 2, 3, 4]
    /// assert_eq!(g.dfs_order(5), [5]);
    /// ```
    ///
    /// # Panics
    /// If `start >= self.node_count()`.
    pub fn dfs_order(&self, start: u32) -> Vec<u32> {
        let mut visited = vec![false; self.node_count()];
        let mut order = Vec::new();
        let mut stack = vec![start];
        while let Some(node) = stack.pop() {
            if std::mem::replace(&mut visited[node as usize], true) {
                continue;
            }
            order.push(node);
            stack.extend(self.neighbors(node).iter().rev().filter(|&&n| !visited[n as usize]));
        }
        order
    }

    /// Component label per node (labels `0..count` in order of each component's
    /// smallest node) and the number of components.
    ///
    /// ```
    /// use mesh_topo::graph::Graph;
    ///
    /// let g = Graph::from_edges(6, &[(4, 5), (2, 0)]);
    /// let (labels, count) = g.connected_components();
    /// assert_eq!(count, 4);
    /// assert_eq!(labels, [0, 1, 0, 2, 3, 3]); // numbered by smallest node: {0, 2}, {1}, {3}, {4, 5}
    /// ```
    pub fn connected_components(&self) -> (Vec<u32>, usize) {
        let n = self.node_count();
        let mut label = vec![u32::MAX; n];
        let mut queue = Vec::new();
        let mut count = 0u32;
        for s in 0..n as u32 {
            if label[s as usize] != u32::MAX {
                continue;
            }
            label[s as usize] = count;
            queue.clear();
            queue.push(s);
            let mut head = 0;
            while head < queue.len() {
                let node = queue[head];
                head += 1;
                for &m in self.neighbors(node) {
                    if label[m as usize] == u32::MAX {
                        label[m as usize] = count;
                        queue.push(m);
                    }
                }
            }
            count += 1;
        }
        (label, count as usize)
    }

    fn bfs_into(&self, start: u32, visited: &mut [bool], order: &mut Vec<u32>) {
        let begin = order.len();
        visited[start as usize] = true;
        order.push(start);
        let mut head = begin;
        while head < order.len() {
            let node = order[head];
            head += 1;
            for &m in self.neighbors(node) {
                if !visited[m as usize] {
                    visited[m as usize] = true;
                    order.push(m);
                }
            }
        }
    }
}

/// Disjoint sets over `0..n` with path halving and union by size.
///
/// ```
/// use mesh_topo::graph::UnionFind;
/// let mut sets = UnionFind::new(4);
/// sets.union(0, 1);
/// sets.union(2, 3);
/// assert!(sets.same(0, 1));
/// assert!(!sets.same(1, 2));
/// assert_eq!(sets.set_count(), 2);
/// let (labels, count) = sets.labels();
/// assert_eq!((labels, count), (vec![0, 0, 1, 1], 2));
/// ```
#[derive(Debug, Clone)]
pub struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
    sets: usize,
}

impl UnionFind {
    /// `n` singleton sets.
    ///
    /// ```
    /// use mesh_topo::graph::UnionFind;
    ///
    /// let mut sets = UnionFind::new(3);
    /// assert_eq!(sets.set_count(), 3);
    /// assert!((0..3).all(|x| sets.find(x) == x));
    /// ```
    ///
    /// # Panics
    /// If `n > u32::MAX` (elements are `u32`).
    pub fn new(n: usize) -> Self {
        assert!(n <= u32::MAX as usize, "union-find of {n} elements: at most u32::MAX");
        Self { parent: (0..n as u32).collect(), size: vec![1; n], sets: n }
    }

    /// Representative of `x`'s set.
    ///
    /// ```
    /// use mesh_topo::graph::UnionFind;
    ///
    /// let mut sets = UnionFind::new(4);
    /// sets.union(0, 1);
    /// sets.union(1, 2);
    /// assert_eq!(sets.find(2), sets.find(0));
    /// assert_eq!(sets.find(3), 3);
    /// ```
    ///
    /// # Panics
    /// If `x` is not an element (`x >= n`): the caller's own index, a programming error
    /// as in [`Graph::from_edges`]. So do [`UnionFind::union`] and [`UnionFind::same`].
    pub fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let grandparent = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = grandparent;
            x = grandparent;
        }
        x
    }

    /// Merges the sets of `a` and `b`; returns false if they were already one set.
    ///
    /// ```
    /// use mesh_topo::graph::UnionFind;
    ///
    /// let mut sets = UnionFind::new(3);
    /// assert!(sets.union(0, 1));
    /// assert!(sets.union(2, 1));
    /// assert!(!sets.union(0, 2)); // already one set
    /// assert_eq!(sets.set_count(), 1);
    /// ```
    ///
    /// # Panics
    /// If `a` or `b` is not an element.
    pub fn union(&mut self, a: u32, b: u32) -> bool {
        let (mut ra, mut rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        if self.size[ra as usize] < self.size[rb as usize] {
            std::mem::swap(&mut ra, &mut rb);
        }
        self.parent[rb as usize] = ra;
        self.size[ra as usize] += self.size[rb as usize];
        self.sets -= 1;
        true
    }

    /// True if `a` and `b` are in the same set.
    ///
    /// ```
    /// use mesh_topo::graph::UnionFind;
    ///
    /// let mut sets = UnionFind::new(3);
    /// sets.union(0, 2);
    /// assert!(sets.same(2, 0));
    /// assert!(!sets.same(0, 1));
    /// ```
    ///
    /// # Panics
    /// If `a` or `b` is not an element.
    pub fn same(&mut self, a: u32, b: u32) -> bool {
        self.find(a) == self.find(b)
    }

    /// Number of disjoint sets.
    ///
    /// ```
    /// use mesh_topo::graph::UnionFind;
    ///
    /// let mut sets = UnionFind::new(5);
    /// assert_eq!(sets.set_count(), 5);
    /// sets.union(0, 1);
    /// sets.union(3, 4);
    /// sets.union(1, 0);
    /// assert_eq!(sets.set_count(), 3);
    /// ```
    pub fn set_count(&self) -> usize {
        self.sets
    }

    /// Dense labels `0..count`, numbered in order of each set's smallest element.
    ///
    /// ```
    /// use mesh_topo::graph::UnionFind;
    ///
    /// let mut sets = UnionFind::new(4);
    /// sets.union(3, 1);
    /// assert_eq!(sets.labels(), (vec![0, 1, 2, 1], 3));
    /// ```
    pub fn labels(&mut self) -> (Vec<u32>, usize) {
        let n = self.parent.len();
        let mut label_of_root = vec![u32::MAX; n];
        let mut labels = vec![0u32; n];
        let mut count = 0u32;
        for x in 0..n as u32 {
            let r = self.find(x);
            if label_of_root[r as usize] == u32::MAX {
                label_of_root[r as usize] = count;
                count += 1;
            }
            labels[x as usize] = label_of_root[r as usize];
        }
        (labels, count as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn dfs_is_preorder_in_insertion_order() {
        let g = Graph::from_edges(5, &[(0, 1), (0, 2), (1, 3), (2, 4)]);
        assert_eq!(g.dfs_order(0), vec![0, 1, 3, 2, 4]);
        assert_eq!(g.bfs_order(0), vec![0, 1, 2, 3, 4]);
        assert_eq!(g.edge_count(), 4);
    }

    #[test]
    #[should_panic(expected = "at most u32::MAX")]
    fn a_graph_of_more_nodes_than_u32_panics_with_a_message() {
        // `node_count + 1` used to wrap, then an index panic.
        Graph::from_edges(usize::MAX, &[]);
    }

    #[test]
    #[should_panic(expected = "at most u32::MAX")]
    fn a_union_find_of_more_elements_than_u32_panics_with_a_message() {
        // `0..n as u32` used to truncate silently: a set count that disagrees with the
        // elements.
        UnionFind::new(u32::MAX as usize + 1);
    }

    proptest! {
        #[test]
        fn union_find_agrees_with_graph_components(n in 1usize..40, raw in prop::collection::vec((0u32..40, 0u32..40), 0..60)) {
            let edges: Vec<(u32, u32)> = raw.into_iter().map(|(a, b)| (a % n as u32, b % n as u32)).collect();
            let g = Graph::from_edges(n, &edges);
            let mut uf = UnionFind::new(n);
            for &(a, b) in &edges { uf.union(a, b); }
            prop_assert_eq!(g.connected_components(), uf.labels());
            let (labels, _) = g.connected_components();
            for s in 0..n as u32 {
                let reach = g.bfs_order(s);
                prop_assert_eq!(reach.len(), labels.iter().filter(|&&l| l == labels[s as usize]).count());
                let mut dfs = g.dfs_order(s);
                let mut bfs = reach.clone();
                dfs.sort_unstable();
                bfs.sort_unstable();
                prop_assert_eq!(dfs, bfs);
            }
        }
    }
}
