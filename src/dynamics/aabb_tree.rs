//! A dynamic bounding-volume tree over axis-aligned boxes, with a fixed capacity.
//!
//! # The tree
//!
//! Every proxy (a box with a `u32` user value and category bits) is a leaf of a binary
//! tree whose internal nodes hold the union of their two children's boxes, so a query
//! descends only into subtrees whose box overlaps the query box. The design is Box2D
//! v3's `b2DynamicTree` (Erin Catto, `src/dynamic_tree.c`; also his GDC 2019 talk
//! "Dynamic Bounding Volume Hierarchies"), written again for fixed capacity:
//!
//! - **Insertion by the surface-area heuristic (SAH).** The expected cost of a query is
//!   proportional to the sum of the surface areas of the internal nodes it may visit
//!   (Goldsmith and Salmon, "Automatic creation of object hierarchies for ray tracing",
//!   1987; MacDonald and Booth, 1990). A new leaf `D` becomes the sibling of the node
//!   `S` that adds the least to that sum: a new parent of area `A(S ∪ D)`, plus the
//!   growth `A(P ∪ D) − A(P)` of every ancestor `P` of `S`. The best sibling is found by
//!   a branch-and-bound descent from the root ([`AabbTree::best_sibling`]): below a node
//!   whose cost so far is `c`, no sibling can cost less than `c + A(D)` plus the growth of
//!   that node, so the descent stops once the best cost found is below both children's
//!   bounds, and otherwise follows the child with the lower bound (Box2D's greedy path;
//!   `A` is half the surface area, `xy + yz + zx`, Box2D's perimeter in 2D).
//! - **Tree rotations** on the way back up (Kopta et al., "Fast, effective BVH updates
//!   for animated scenes", 2012, as in Box2D's `b2RotateNodes`): at each ancestor `A`
//!   with children `B` and `C`, swapping `B` with a grandchild under `C` (or `C` with one
//!   under `B`) changes the area of exactly one internal node; the swap that shrinks it
//!   most is made. This keeps the tree shallow when proxies move (Box2D rotates only on
//!   creation and relies on periodic rebuilds; here every insertion, moves included,
//!   rotates, and there is no rebuild).
//! - **Removal** replaces the leaf's parent by the leaf's sibling and refits the
//!   ancestors' boxes and heights. **Moving** a proxy to a box inside its parent's box
//!   keeps its place and refits the ancestors (up to the first box the refit does not
//!   change): the box still belongs under that parent, and the search and rotations are
//!   saved. Any other move is a removal and an insertion below the lowest ancestor whose
//!   box held the new box (the root when none did): the search and the rotations run
//!   over that subtree only, and the ancestors above it are refitted up to the first box
//!   that does not change. Removals refit the same way. The proxy keeps its id.
//!
//! # All pairs in one walk
//!
//! [`AabbTree::overlapping_pairs`] finds every pair of overlapping leaves with at least
//! one *marked* leaf (a body that moved) by walking the tree against itself, as
//! bounding-volume-tree traversals do (rapier's broad phase works this way): from the
//! pair (root, root), a node paired with itself visits its two children each with itself
//! and the two together; two different nodes whose boxes overlap split the larger one
//! (by area; an internal node before a leaf); two leaves are a pair. A pair of nodes is
//! visited only when one of them holds a marked leaf (a flag set on the path from every
//! marked leaf up), one holds a leaf of a category asked for, and their boxes meet. The
//! upper levels of the tree are then crossed once for all leaves, where one query per
//! moved leaf crosses them again and again: in the `spheres` scene's first 60 steps the
//! step runs 16 % fewer instructions. Each pair of nodes is visited at most once, so each
//! leaf pair is reported once. The walk is depth first with a fixed stack (about three
//! entries per level); if it does not fit, the walk reports so and the caller falls back
//! to one query per leaf.
//!
//! # Capacity and bounds
//!
//! `N` proxies need at most `2N − 1` nodes (`N` leaves, `N − 1` internal nodes), stored
//! inline as `N` pairs. Free nodes form a list threaded through their `parent` field;
//! nodes never used yet are handed out from a bump index, so an empty tree needs no
//! initialisation loop (`new` is `const`). An insertion beyond `N` proxies returns `None`.
//! There is no recursion, every loop has an explicit iteration cap, and every node access
//! is checked (`get`), so a corrupt index ends a walk instead of panicking.
//!
//! A query is a depth-first walk with a fixed stack of [`QUERY_STACK`] entries. A walk
//! holds at most `height + 1` entries, so a tree taller than that (a pathological
//! history) is answered by a linear scan of the leaves instead, and a push that does not
//! fit (which the height check rules out) scans the leaves under the node it could not
//! push: either way the answer is complete.
//!
//! # Determinism
//!
//! The shape of the tree depends on the order of the insertions, moves and removals that
//! built it, and so does the order in which a query visits the leaves. The set of leaves
//! a query visits does not: it is every leaf whose box overlaps the query box (and whose
//! category matches the mask). Callers must use the answer as a set.

use heapless::Vec as HVec;

use crate::math::Aabb;

/// No node: the parent of the root, the root of an empty tree, the end of the free list.
pub(crate) const NULL: u32 = u32::MAX;

/// Entries of a query's stack: enough for any tree up to height 63. A tree of `n`
/// leaves kept in shape by the SAH and rotations is typically about `2 log₂ n` high (26
/// for 8192 leaves).
pub(crate) const QUERY_STACK: usize = 64;

/// What a node is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// On the free list or never used.
    Free,
    /// A proxy.
    Leaf,
    /// The union of two children.
    Internal,
}

/// One node (40 bytes).
#[derive(Clone, Copy, Debug)]
struct Node {
    /// A leaf's box, or the union of an internal node's children's boxes (m).
    aabb: Aabb,
    /// The parent ([`NULL`] for the root); for a free node, the next free node.
    parent: u32,
    /// First child of an internal node; [`NULL`] for a leaf.
    child1: u32,
    /// Second child of an internal node; for a leaf, its user value.
    child2: u32,
    /// 0 for a leaf, `1 + max` of the children's heights otherwise (saturating).
    height: u16,
    /// A leaf's category bits; the union of the children's for an internal node.
    category: u8,
    /// Free, leaf or internal.
    kind: Kind,
}

impl Node {
    /// A free node.
    const FREE: Node = Node {
        aabb: Aabb::new(crate::math::Vec3::ZERO, crate::math::Vec3::ZERO),
        parent: NULL,
        child1: NULL,
        child2: NULL,
        height: 0,
        category: 0,
        kind: Kind::Free,
    };
}

/// The cost of a box in the surface-area heuristic: half its surface area,
/// `xy + yz + zx` (m²).
#[inline]
fn area(b: &Aabb) -> f32 {
    let d = b.max - b.min;
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// A dynamic AABB tree of at most `N` proxies (module docs).
#[derive(Clone, Debug)]
pub(crate) struct AabbTree<const N: usize> {
    /// `2N` nodes; node `i` is `nodes[i / 2][i % 2]`.
    nodes: [[Node; 2]; N],
    /// The root, or [`NULL`] when empty.
    root: u32,
    /// Head of the free list (released nodes), or [`NULL`].
    free: u32,
    /// Nodes `fresh..2N` have never been used.
    fresh: u32,
    /// Number of leaves (proxies).
    leaves: u32,
}

impl<const N: usize> AabbTree<N> {
    /// Nodes in storage: `2N`, within `u32`.
    const NODES: u32 = {
        let n = N.saturating_mul(2);
        if n >= NULL as usize {
            NULL - 1
        } else {
            n as u32
        }
    };

    /// An empty tree.
    pub const fn new() -> Self {
        AabbTree {
            nodes: [[Node::FREE; 2]; N],
            root: NULL,
            free: NULL,
            fresh: 0,
            leaves: 0,
        }
    }

    /// Back to [`AabbTree::new`]'s state where it lies: [`AabbTree::clear`], and every
    /// node free as a new tree's.
    pub fn reset(&mut self) {
        self.clear();
        self.nodes.fill([Node::FREE; 2]);
    }

    /// Remove every proxy. Proxy ids handed out before are invalid afterwards.
    pub fn clear(&mut self) {
        self.root = NULL;
        self.free = NULL;
        self.fresh = 0;
        self.leaves = 0;
    }

    /// Add a proxy with box `aabb`, user value `user` and category bits `category`
    /// (which [`AabbTree::query`] matches against its mask). Returns the proxy id, which
    /// stays the proxy's until it is removed, or `None` when the tree holds `N` proxies.
    pub fn insert(&mut self, aabb: Aabb, user: u32, category: u8) -> Option<u32> {
        if self.leaves as usize >= N {
            return None;
        }
        let leaf = self.allocate(Node {
            aabb,
            parent: NULL,
            child1: NULL,
            child2: user,
            height: 0,
            category,
            kind: Kind::Leaf,
        })?;
        if !self.insert_leaf(leaf, self.root) {
            // Unreachable: fewer than `N` leaves leave a node for the new parent.
            self.release(leaf);
            return None;
        }
        self.leaves += 1;
        Some(leaf)
    }

    /// Remove a proxy; false (and no change) when `proxy` is not one.
    pub fn remove(&mut self, proxy: u32) -> bool {
        if !self.is_leaf(proxy) {
            return false;
        }
        self.remove_leaf(proxy);
        self.release(proxy);
        self.leaves = self.leaves.saturating_sub(1);
        true
    }

    /// Give a proxy a new box: refitted in place when the box stays inside its parent's,
    /// else removed and inserted again (module docs), keeping its id. False (and no
    /// change) when `proxy` is not one.
    pub fn move_proxy(&mut self, proxy: u32, aabb: Aabb) -> bool {
        if !self.is_leaf(proxy) {
            return false;
        }
        // A box that stays inside its parent's keeps its place: the ancestors are refitted
        // (up to the first one whose box does not change), no search, no rotation.
        let parent = self.node(proxy).map_or(NULL, |n| n.parent);
        if self.node(parent).is_some_and(|p| p.aabb.contains(&aabb)) {
            if let Some(n) = self.node_mut(proxy) {
                n.aabb = aabb;
            }
            self.refit_until_unchanged(parent);
            return true;
        }
        // Else the search starts at the lowest ancestor whose box holds the new box (the
        // root when none does), whose own ancestors need not grow: a proxy moving a
        // little is settled near where it was, in a few levels instead of the whole
        // height (the same branch and bound, over that subtree).
        let top = self.lowest_holder(parent, &aabb);
        self.remove_leaf(proxy);
        if let Some(n) = self.node_mut(proxy) {
            n.aabb = aabb;
        }
        let top = if top == NULL { self.root } else { top };
        if self.insert_leaf(proxy, top) {
            return true;
        }
        // Unreachable: the removal freed the node the insertion needs. Drop the proxy
        // rather than leave it detached.
        self.release(proxy);
        self.leaves = self.leaves.saturating_sub(1);
        false
    }

    /// Number of proxies.
    pub fn len(&self) -> usize {
        self.leaves as usize
    }

    /// A proxy's box.
    pub fn aabb(&self, proxy: u32) -> Option<Aabb> {
        self.leaf(proxy).map(|n| n.aabb)
    }

    /// A proxy's category bits.
    pub fn category(&self, proxy: u32) -> Option<u8> {
        self.leaf(proxy).map(|n| n.category)
    }

    /// Call `f(user)` for every proxy whose box overlaps (or touches) `aabb` and whose
    /// category shares a bit with `mask`, each once, in an order that depends on the
    /// tree's shape (module docs: use the answer as a set).
    pub fn query<F: FnMut(u32)>(&self, aabb: &Aabb, mask: u8, mut f: F) {
        self.query_with_stack::<QUERY_STACK, F>(aabb, mask, &mut f);
    }

    /// Call `f(user_a, user_b)` once for every pair of distinct leaves whose boxes overlap
    /// (or touch), at least one of them `marked` (by its user value) and at least one of
    /// them of a category in `needed`, in an order that depends on the tree's shape (use
    /// the answer as a set): one walk of the tree against itself (module docs, "All
    /// pairs in one walk"). False when more than `S` node pairs wait at once: the walk
    /// stops there, having called `f` for some of the pairs, and the caller must start
    /// over another way.
    pub fn overlapping_pairs<const S: usize>(
        &self,
        marked: impl Fn(u32) -> bool,
        needed: u8,
        mut f: impl FnMut(u32, u32),
    ) -> bool {
        // Which subtrees hold a marked leaf: from each marked leaf up to the first
        // ancestor already known to (each node is flagged once).
        let mut flagged = [[false; 2]; N];
        let flag = |flagged: &[[bool; 2]; N], i: u32| {
            let i = i as usize;
            flagged
                .get(i / 2)
                .and_then(|p| p.get(i % 2))
                .copied()
                .unwrap_or(false)
        };
        for leaf in 0..self.fresh {
            let Some(n) = self.leaf(leaf) else { continue };
            if !marked(n.child2) {
                continue;
            }
            let mut at = leaf;
            for _ in 0..=Self::NODES {
                let i = at as usize;
                let Some(slot) = flagged.get_mut(i / 2).and_then(|p| p.get_mut(i % 2)) else {
                    break;
                };
                if *slot {
                    break;
                }
                *slot = true;
                at = self.node(at).map_or(NULL, |n| n.parent);
            }
        }
        // A pair of distinct subtrees is worth a visit when one holds a marked leaf, one a
        // leaf of a needed category, and their boxes meet; a subtree against itself when
        // it holds a marked leaf and a needed one, and two leaves or more.
        let worth = |flagged: &[[bool; 2]; N], a: u32, b: u32| {
            let (Some(na), Some(nb)) = (self.node(a), self.node(b)) else {
                return false;
            };
            (flag(flagged, a) || flag(flagged, b))
                && (na.category | nb.category) & needed != 0
                && na.aabb.overlaps(&nb.aabb)
        };
        let worth_alone = |flagged: &[[bool; 2]; N], a: u32| {
            self.node(a).is_some_and(|n| {
                n.kind == Kind::Internal && n.category & needed != 0 && flag(flagged, a)
            })
        };
        let mut stack: HVec<(u32, u32), S> = HVec::new();
        if !worth_alone(&flagged, self.root) {
            return true;
        }
        if stack.push((self.root, self.root)).is_err() {
            return false;
        }
        // Every pair of nodes is visited at most once.
        let mut budget = u64::from(Self::NODES) * u64::from(Self::NODES);
        while let Some((a, b)) = stack.pop() {
            if budget == 0 {
                return false;
            }
            budget -= 1;
            let (Some(&na), Some(&nb)) = (self.node(a), self.node(b)) else {
                continue;
            };
            let mut push = |pair: (u32, u32)| stack.push(pair).is_ok();
            let fits = if a == b {
                // A subtree against itself: each child against itself, and the two
                // children against each other.
                let (c1, c2) = (na.child1, na.child2);
                (!worth_alone(&flagged, c1) || push((c1, c1)))
                    && (!worth_alone(&flagged, c2) || push((c2, c2)))
                    && (!worth(&flagged, c1, c2) || push((c1, c2)))
            } else if na.kind == Kind::Leaf && nb.kind == Kind::Leaf {
                f(na.child2, nb.child2);
                true
            } else {
                // Descend into the internal one (the larger when both are).
                let split_a = nb.kind == Kind::Leaf
                    || (na.kind == Kind::Internal && area(&na.aabb) >= area(&nb.aabb));
                let (parent, other) = if split_a { (na, b) } else { (nb, a) };
                let (c1, c2) = (parent.child1, parent.child2);
                (!worth(&flagged, c1, other) || push((c1, other)))
                    && (!worth(&flagged, c2, other) || push((c2, other)))
            };
            if !fits {
                return false;
            }
        }
        true
    }

    /// [`AabbTree::query`] with a stack of `S` entries.
    fn query_with_stack<const S: usize, F: FnMut(u32)>(&self, aabb: &Aabb, mask: u8, f: &mut F) {
        let Some(root) = self.node(self.root) else {
            return;
        };
        if usize::from(root.height) >= S {
            // The walk could need more than `S` entries.
            self.scan_leaves(NULL, aabb, mask, f);
            return;
        }
        // Only nodes that match (category and box) are pushed: each is tested once, as a
        // child, before it costs a push and a pop.
        let matches = |n: &Node| n.category & mask != 0 && n.aabb.overlaps(aabb);
        if !matches(root) {
            return;
        }
        let mut stack: HVec<u32, S> = HVec::new();
        let _ = stack.push(self.root);
        // Every node is pushed at most once.
        let mut budget = Self::NODES;
        while let Some(i) = stack.pop() {
            if budget == 0 {
                break;
            }
            budget -= 1;
            let Some(n) = self.node(i) else {
                continue;
            };
            match n.kind {
                Kind::Leaf => f(n.child2),
                Kind::Internal => {
                    for child in [n.child2, n.child1] {
                        if !self.node(child).is_some_and(matches) {
                            continue;
                        }
                        if stack.push(child).is_err() {
                            self.scan_leaves(child, aabb, mask, f);
                        }
                    }
                }
                Kind::Free => {}
            }
        }
    }

    /// The linear fallback of a query: every leaf that matches, in node order; with
    /// `under` not [`NULL`], only the leaves in `under`'s subtree (found by walking up
    /// the parents, at most `2N` steps each).
    fn scan_leaves(&self, under: u32, aabb: &Aabb, mask: u8, f: &mut dyn FnMut(u32)) {
        for i in 0..self.fresh {
            let Some(n) = self.leaf(i) else {
                continue;
            };
            if n.category & mask == 0 || !n.aabb.overlaps(aabb) {
                continue;
            }
            if under == NULL || self.is_below(i, under) {
                f(n.child2);
            }
        }
    }

    /// True when `node` is `ancestor` or lies in its subtree.
    fn is_below(&self, node: u32, ancestor: u32) -> bool {
        let mut at = node;
        for _ in 0..=Self::NODES {
            if at == ancestor {
                return true;
            }
            match self.node(at) {
                Some(n) if n.parent != NULL => at = n.parent,
                _ => return false,
            }
        }
        false
    }

    // ----- nodes -------------------------------------------------------------------

    #[inline]
    fn node(&self, i: u32) -> Option<&Node> {
        let i = i as usize;
        self.nodes.get(i / 2)?.get(i % 2)
    }

    #[inline]
    fn node_mut(&mut self, i: u32) -> Option<&mut Node> {
        let i = i as usize;
        self.nodes.get_mut(i / 2)?.get_mut(i % 2)
    }

    /// Node `i` if it is a leaf.
    #[inline]
    fn leaf(&self, i: u32) -> Option<&Node> {
        self.node(i).filter(|n| n.kind == Kind::Leaf)
    }

    fn is_leaf(&self, i: u32) -> bool {
        self.leaf(i).is_some()
    }

    fn set_parent(&mut self, i: u32, parent: u32) {
        if let Some(n) = self.node_mut(i) {
            n.parent = parent;
        }
    }

    /// Make `new` the child of `parent` that `old` was (the root when `parent` is
    /// [`NULL`]).
    fn replace_child(&mut self, parent: u32, old: u32, new: u32) {
        if parent == NULL {
            self.root = new;
            return;
        }
        if let Some(p) = self.node_mut(parent) {
            if p.child1 == old {
                p.child1 = new;
            } else if p.child2 == old {
                p.child2 = new;
            }
        }
    }

    /// Take a node from the free list, else a fresh one, and fill it with `node`.
    fn allocate(&mut self, node: Node) -> Option<u32> {
        let i = if self.free != NULL {
            let i = self.free;
            self.free = self.node(i).map_or(NULL, |n| n.parent);
            i
        } else if self.fresh < Self::NODES {
            self.fresh += 1;
            self.fresh - 1
        } else {
            return None;
        };
        *self.node_mut(i)? = node;
        Some(i)
    }

    /// Put node `i` on the free list.
    fn release(&mut self, i: u32) {
        let next = self.free;
        if let Some(n) = self.node_mut(i) {
            *n = Node {
                parent: next,
                ..Node::FREE
            };
            self.free = i;
        }
    }

    /// Set an internal node's box, height and category from its children.
    fn refit(&mut self, i: u32) {
        let Some(&n) = self.node(i) else {
            return;
        };
        let (Some(&c1), Some(&c2)) = (self.node(n.child1), self.node(n.child2)) else {
            return;
        };
        if let Some(n) = self.node_mut(i) {
            n.aabb = c1.aabb.union(&c2.aabb);
            n.height = c1.height.max(c2.height).saturating_add(1);
            n.category = c1.category | c2.category;
        }
    }

    /// Refit `start` and its ancestors, up to the first whose box, height and categories
    /// the refit leaves as they were (above it nothing changes).
    fn refit_until_unchanged(&mut self, start: u32) {
        let mut at = start;
        for _ in 0..=Self::NODES {
            let Some(&before) = self.node(at) else {
                return;
            };
            if before.kind != Kind::Internal {
                return;
            }
            self.refit(at);
            let unchanged = self.node(at).is_some_and(|n| {
                n.aabb == before.aabb && n.height == before.height && n.category == before.category
            });
            if unchanged {
                return;
            }
            at = before.parent;
        }
    }

    /// Refit and rotate `start` and its ancestors up to `stop` (included; the root when
    /// `stop` is not on the path), then refit the ancestors above `stop` up to the first
    /// the refit leaves as it was.
    fn refit_and_rotate_up_to(&mut self, start: u32, stop: u32) {
        let mut at = start;
        // The path to the root is at most as long as the tree is high.
        for _ in 0..=Self::NODES {
            let Some(n) = self.node(at) else {
                return;
            };
            if n.kind != Kind::Internal {
                return;
            }
            let parent = n.parent;
            self.refit(at);
            // Rotations change what lies below `at`, never `at`'s place or box.
            self.rotate(at);
            if at == stop {
                self.refit_until_unchanged(parent);
                return;
            }
            at = parent;
        }
    }

    /// The lowest of `start` and its ancestors whose box holds `aabb`; [`NULL`] when none
    /// does.
    fn lowest_holder(&self, start: u32, aabb: &Aabb) -> u32 {
        let mut at = start;
        for _ in 0..=Self::NODES {
            match self.node(at) {
                Some(n) if n.aabb.contains(aabb) => return at,
                Some(n) => at = n.parent,
                None => return NULL,
            }
        }
        NULL
    }

    // ----- insertion and removal -------------------------------------------------------

    /// Hang the detached leaf `leaf` into the tree beside its best sibling under `top`
    /// (the root, or an ancestor whose box held the leaf's; module docs), rotating the
    /// nodes from the new parent up to `top`'s place; false when no node is left for the
    /// new parent.
    fn insert_leaf(&mut self, leaf: u32, top: u32) -> bool {
        let Some(&l) = self.node(leaf) else {
            return false;
        };
        if self.root == NULL {
            self.set_parent(leaf, NULL);
            self.root = leaf;
            return true;
        }
        let sibling = self.best_sibling(&l.aabb, top);
        let Some(&s) = self.node(sibling) else {
            return false;
        };
        let Some(parent) = self.allocate(Node {
            aabb: s.aabb.union(&l.aabb),
            parent: s.parent,
            child1: sibling,
            child2: leaf,
            height: s.height.saturating_add(1),
            category: s.category | l.category,
            kind: Kind::Internal,
        }) else {
            return false;
        };
        self.replace_child(s.parent, sibling, parent);
        self.set_parent(sibling, parent);
        self.set_parent(leaf, parent);
        // The new parent takes the sibling's place: when that was `top`'s, the parent is
        // the last node to rotate.
        let stop = if sibling == top { parent } else { top };
        self.refit_and_rotate_up_to(parent, stop);
        true
    }

    /// Unhook `leaf` (which stays allocated): its sibling takes its parent's place, and
    /// the ancestors are refitted.
    fn remove_leaf(&mut self, leaf: u32) {
        if leaf == self.root {
            self.root = NULL;
            return;
        }
        let Some(parent) = self.node(leaf).map(|n| n.parent) else {
            return;
        };
        let Some(&p) = self.node(parent) else {
            return;
        };
        let sibling = if p.child1 == leaf { p.child2 } else { p.child1 };
        self.replace_child(p.parent, parent, sibling);
        self.set_parent(sibling, p.parent);
        self.set_parent(leaf, NULL);
        self.release(parent);
        self.refit_until_unchanged(p.parent);
    }

    /// The node the new box `d` should become the sibling of: the least SAH cost, by
    /// Box2D's branch-and-bound descent (module docs).
    ///
    /// At a node `X` on the path, with `inherited` the growth of `X`'s strict ancestors
    /// by `d`, making `d` the sibling of `X` costs `A(X ∪ D) + inherited`. For a child
    /// `K` of `X` the growth passed down becomes `inherited + A(X ∪ D) − A(X)`; a leaf
    /// child's cost is then exact, and below an internal child nothing costs less than
    /// `inherited' + A(K ∪ D) + min(A(D) − A(K), 0)` (either `K` itself is the sibling,
    /// or `K` grows and a new parent of at least `A(D)` appears below it). Ties between
    /// two internal children's bounds (a box inside both) go to the nearer centre.
    fn best_sibling(&self, d: &Aabb, top: u32) -> u32 {
        let Some(root) = self.node(top) else {
            return top;
        };
        let area_d = area(d);
        let center_d = d.center();
        let mut area_here = area(&root.aabb);
        let mut direct = area(&root.aabb.union(d));
        let mut inherited = 0.0f32;
        let mut best = top;
        let mut best_cost = direct;
        let mut at = top;
        for _ in 0..=Self::NODES {
            let Some(n) = self.node(at) else {
                break;
            };
            if n.kind != Kind::Internal {
                break;
            }
            let cost = direct + inherited;
            if cost < best_cost {
                best = at;
                best_cost = cost;
            }
            inherited += direct - area_here;
            let (Some(c1), Some(c2)) = (self.node(n.child1), self.node(n.child2)) else {
                break;
            };
            // Per child: (its direct cost, its area, the lower bound below it).
            let mut look = |child: u32, c: &Node| {
                let direct_c = area(&c.aabb.union(d));
                if c.kind == Kind::Internal {
                    let area_c = area(&c.aabb);
                    let bound =
                        inherited + direct_c + crate::math::scalar::min(area_d - area_c, 0.0);
                    (direct_c, area_c, bound)
                } else {
                    let cost_c = direct_c + inherited;
                    if cost_c < best_cost {
                        best = child;
                        best_cost = cost_c;
                    }
                    (direct_c, 0.0, f32::INFINITY)
                }
            };
            let (direct1, area1, mut bound1) = look(n.child1, c1);
            let (direct2, area2, mut bound2) = look(n.child2, c2);
            let (internal1, internal2) = (c1.kind == Kind::Internal, c2.kind == Kind::Internal);
            if !internal1 && !internal2 {
                break;
            }
            if best_cost <= bound1 && best_cost <= bound2 {
                break;
            }
            if bound1 == bound2 && internal1 {
                // `d` lies inside both: no area tells them apart. The nearer centre.
                bound1 = (c1.aabb.center() - center_d).length_squared();
                bound2 = (c2.aabb.center() - center_d).length_squared();
            }
            if bound1 < bound2 && internal1 {
                at = n.child1;
                area_here = area1;
                direct = direct1;
            } else {
                at = n.child2;
                area_here = area2;
                direct = direct2;
            }
        }
        best
    }

    /// One tree rotation at the internal node `a` with children `b` and `c`, if one
    /// helps (module docs): moving `b` down in place of a child `y` of `c` (which moves
    /// up beside `c`) leaves every internal node's box as it was except `c`'s, which
    /// becomes `b ∪ z` for `c`'s other child `z`; symmetrically for `c` under `b`. Of the
    /// up to four swaps, the one that shrinks that box's area most is made, none if none
    /// shrinks it.
    fn rotate(&mut self, a: u32) {
        let Some(&na) = self.node(a) else {
            return;
        };
        if na.kind != Kind::Internal || na.height < 2 {
            return;
        }
        // (the child of `a` that moves down, the child of the other that moves up)
        let mut best: Option<(u32, u32)> = None;
        let mut best_delta = 0.0f32;
        for (down, other) in [(na.child1, na.child2), (na.child2, na.child1)] {
            let (Some(&nd), Some(&no)) = (self.node(down), self.node(other)) else {
                return;
            };
            if no.kind != Kind::Internal {
                continue;
            }
            let area_other = area(&no.aabb);
            for (up, stays) in [(no.child1, no.child2), (no.child2, no.child1)] {
                let Some(ns) = self.node(stays) else {
                    return;
                };
                let delta = area(&nd.aabb.union(&ns.aabb)) - area_other;
                if delta < best_delta {
                    best = Some((down, up));
                    best_delta = delta;
                }
            }
        }
        let Some((down, up)) = best else {
            return;
        };
        let other = if na.child1 == down {
            na.child2
        } else {
            na.child1
        };
        self.replace_child(a, down, up);
        self.replace_child(other, up, down);
        self.set_parent(down, other);
        self.set_parent(up, a);
        self.refit(other);
        self.refit(a);
    }
}

#[cfg(test)]
impl<const N: usize> AabbTree<N> {
    /// Height of the tree: 0 for a single leaf (or none).
    pub fn height(&self) -> u16 {
        self.node(self.root).map_or(0, |n| n.height)
    }

    /// Check the structure: parents and children agree, every internal node's box,
    /// height and category are those of its children, every leaf's box lies inside all
    /// its ancestors', the leaf count is right, and every node is reachable from the root
    /// or free exactly once.
    pub fn validate(&self) -> Result<(), std::string::String> {
        use std::format;
        let mut seen = std::vec![false; Self::NODES as usize];
        let mut leaves = 0u32;
        let mut stack = std::vec::Vec::new();
        if self.root != NULL {
            if self.node(self.root).map(|n| n.parent) != Some(NULL) {
                return Err(format!("root {} has a parent", self.root));
            }
            stack.push(self.root);
        }
        while let Some(i) = stack.pop() {
            let n = *self.node(i).ok_or(format!("node {i} out of range"))?;
            if i >= self.fresh || core::mem::replace(&mut seen[i as usize], true) {
                return Err(format!("node {i} fresh or reached twice"));
            }
            match n.kind {
                Kind::Free => return Err(format!("free node {i} in the tree")),
                Kind::Leaf => {
                    leaves += 1;
                    if n.height != 0 || n.child1 != NULL {
                        return Err(format!("leaf {i} malformed"));
                    }
                    // Inside every ancestor.
                    let mut at = n.parent;
                    let mut steps = 0;
                    while at != NULL {
                        let p = self.node(at).ok_or("bad parent")?;
                        if !p.aabb.contains(&n.aabb) {
                            return Err(format!("leaf {i} sticks out of ancestor {at}"));
                        }
                        at = p.parent;
                        steps += 1;
                        if steps > Self::NODES {
                            return Err("parent cycle".into());
                        }
                    }
                }
                Kind::Internal => {
                    let c1 = *self.node(n.child1).ok_or("bad child1")?;
                    let c2 = *self.node(n.child2).ok_or("bad child2")?;
                    if c1.parent != i || c2.parent != i {
                        return Err(format!("children of {i} name another parent"));
                    }
                    if n.height != 1 + c1.height.max(c2.height) {
                        return Err(format!("height of {i}"));
                    }
                    if n.category != c1.category | c2.category {
                        return Err(format!("category of {i}"));
                    }
                    if n.aabb != c1.aabb.union(&c2.aabb) {
                        return Err(format!("box of {i} is not its children's union"));
                    }
                    stack.push(n.child1);
                    stack.push(n.child2);
                }
            }
        }
        if leaves != self.leaves {
            return Err(format!(
                "{leaves} leaves reachable, {} counted",
                self.leaves
            ));
        }
        let mut at = self.free;
        while at != NULL {
            let n = self.node(at).ok_or("bad free link")?;
            if at >= self.fresh || n.kind != Kind::Free || seen[at as usize] {
                return Err(format!("free node {at} bad or in the tree"));
            }
            seen[at as usize] = true;
            at = n.parent;
        }
        if let Some(i) = (0..self.fresh).find(|&i| !seen[i as usize]) {
            return Err(format!("node {i} lost"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::rng::SplitMix64;
    use std::vec::Vec;

    fn random_box(rng: &mut SplitMix64, spread: f32) -> Aabb {
        let c = Vec3::new(
            rng.range(-spread, spread),
            rng.range(-spread, spread),
            rng.range(-spread, spread),
        );
        let h = Vec3::new(
            rng.range(0.0, 1.0),
            rng.range(0.0, 1.0),
            rng.range(0.0, 1.0),
        );
        Aabb::from_center_half(c, h)
    }

    /// The users a query reports, sorted; each at most once.
    fn answer<const N: usize>(tree: &AabbTree<N>, q: &Aabb, mask: u8) -> Vec<u32> {
        let mut out = Vec::new();
        tree.query(q, mask, |u| out.push(u));
        let n = out.len();
        out.sort_unstable();
        out.dedup();
        assert_eq!(out.len(), n, "a leaf reported twice");
        out
    }

    /// Random insert, move and remove sequences against a plain list: every random query
    /// box (and mask) gets the same set of users, and the structure stays valid.
    #[test]
    fn matches_brute_force_over_random_edits() {
        const N: usize = 96;
        for seed in 1..=8u64 {
            let mut rng = SplitMix64::new(seed);
            let mut tree: AabbTree<N> = AabbTree::new();
            // user -> (proxy, box, category)
            let mut live: Vec<Option<(u32, Aabb, u8)>> = std::vec![None; N];
            for round in 0..400 {
                let user = (rng.next_u64() % N as u64) as u32;
                let spread = if seed % 2 == 0 { 4.0 } else { 20.0 };
                match live[user as usize] {
                    None => {
                        let b = random_box(&mut rng, spread);
                        let cat = 1u8 << (rng.next_u64() % 3);
                        let p = tree.insert(b, user, cat).expect("room");
                        live[user as usize] = Some((p, b, cat));
                    }
                    Some((p, old, cat)) => {
                        if rng.next_u64().is_multiple_of(3) {
                            assert!(tree.remove(p));
                            assert!(!tree.remove(p), "removed twice");
                            live[user as usize] = None;
                        } else {
                            // Mostly small moves, sometimes a jump, sometimes a
                            // shrink (inside the parent's box: refitted in place).
                            let b = if rng.next_u64().is_multiple_of(4) {
                                random_box(&mut rng, spread)
                            } else if rng.next_u64().is_multiple_of(3) {
                                Aabb::from_center_half(old.center(), old.half_extents() * 0.5)
                            } else {
                                let d = Vec3::new(
                                    rng.range(-0.5, 0.5),
                                    rng.range(-0.5, 0.5),
                                    rng.range(-0.5, 0.5),
                                );
                                old.translated(d)
                            };
                            assert!(tree.move_proxy(p, b));
                            assert_eq!(tree.aabb(p), Some(b));
                            live[user as usize] = Some((p, b, cat));
                        }
                    }
                }
                tree.validate()
                    .unwrap_or_else(|e| panic!("seed {seed} round {round}: {e}"));
                assert_eq!(tree.len(), live.iter().flatten().count());
                for _ in 0..4 {
                    let q = random_box(&mut rng, spread);
                    let mask = [0b111u8, 0b001, 0b110][(rng.next_u64() % 3) as usize];
                    let expected: Vec<u32> = (0..N as u32)
                        .filter(|&u| {
                            live[u as usize]
                                .is_some_and(|(_, b, c)| c & mask != 0 && b.overlaps(&q))
                        })
                        .collect();
                    assert_eq!(
                        answer(&tree, &q, mask),
                        expected,
                        "seed {seed} round {round}"
                    );
                }
            }
        }
    }

    /// The pairs `(low, high)` of users the walk reports, sorted; each unordered pair at
    /// most once. `None` when the walk's stack of `S` overflowed.
    fn walked<const N: usize, const S: usize>(
        tree: &AabbTree<N>,
        marked: &[bool],
        needed: u8,
    ) -> Option<Vec<(u32, u32)>> {
        let mut out = Vec::new();
        let is_marked = |u: u32| marked.get(u as usize).copied().unwrap_or(false);
        let complete = tree.overlapping_pairs::<S>(is_marked, needed, |a, b| {
            assert_ne!(a, b, "a leaf paired with itself");
            out.push((a.min(b), a.max(b)));
        });
        let n = out.len();
        out.sort_unstable();
        out.dedup();
        assert_eq!(out.len(), n, "a pair reported twice");
        complete.then_some(out)
    }

    /// The walk of the tree against itself against every pair of live proxies: on random
    /// trees (random edits, as above), random marks and each category mask, it reports
    /// exactly the pairs whose boxes overlap, with a marked user and a needed category;
    /// with a stack of 4 it may give up (reported), never report a wrong pair.
    #[test]
    fn overlapping_pairs_match_brute_force() {
        const N: usize = 80;
        let mut walks = 0;
        let mut gave_up = 0;
        for seed in 1..=12u64 {
            let mut rng = SplitMix64::new(100 + seed);
            let mut tree: AabbTree<N> = AabbTree::new();
            let mut live: Vec<Option<(u32, Aabb, u8)>> = std::vec![None; N];
            let spread = [3.0, 8.0, 30.0][(seed % 3) as usize];
            for round in 0..150 {
                let user = (rng.next_u64() % N as u64) as u32;
                match live[user as usize] {
                    Some((p, _, cat)) if rng.next_u64().is_multiple_of(2) => {
                        let b = random_box(&mut rng, spread);
                        assert!(tree.move_proxy(p, b));
                        live[user as usize] = Some((p, b, cat));
                    }
                    Some((p, _, _)) => {
                        assert!(tree.remove(p));
                        live[user as usize] = None;
                    }
                    None => {
                        let b = random_box(&mut rng, spread);
                        let cat = 1u8 << (rng.next_u64() % 3);
                        let p = tree.insert(b, user, cat).expect("room");
                        live[user as usize] = Some((p, b, cat));
                    }
                }
                if round % 10 != 9 {
                    continue;
                }
                let share = 1 + rng.next_u64() % 4;
                let marked: Vec<bool> = (0..N)
                    .map(|_| rng.next_u64().is_multiple_of(share))
                    .collect();
                for needed in [0b100u8, 0b111, 0b011] {
                    let mut expected = Vec::new();
                    for a in 0..N as u32 {
                        for b in a + 1..N as u32 {
                            let (Some((_, ba, ca)), Some((_, bb, cb))) =
                                (live[a as usize], live[b as usize])
                            else {
                                continue;
                            };
                            if ba.overlaps(&bb)
                                && (marked[a as usize] || marked[b as usize])
                                && (ca | cb) & needed != 0
                            {
                                expected.push((a, b));
                            }
                        }
                    }
                    let got = walked::<N, 256>(&tree, &marked, needed);
                    assert_eq!(got.as_ref(), Some(&expected), "seed {seed} round {round}");
                    walks += 1;
                    match walked::<N, 4>(&tree, &marked, needed) {
                        Some(small) => assert_eq!(small, expected),
                        None => gave_up += 1,
                    }
                }
            }
        }
        assert!(walks > 400, "{walks} walks");
        // A stack of 4 is too small for some of these trees: the give-up path ran.
        assert!(gave_up > 0, "no walk overflowed a stack of 4");
    }

    /// A full tree refuses one more proxy and is unchanged; removing one makes room. The
    /// SAH with rotations keeps a grid of boxes shallow.
    #[test]
    fn capacity_and_height() {
        const N: usize = 512;
        let mut tree: AabbTree<N> = AabbTree::new();
        for i in 0..N as u32 {
            let c = Vec3::new((i % 8) as f32, ((i / 8) % 8) as f32, (i / 64) as f32);
            let b = Aabb::from_center_half(c, Vec3::splat(0.6));
            assert_eq!(tree.insert(b, i, 1).map(|_| ()), Some(()));
        }
        tree.validate().unwrap();
        let extra = Aabb::from_center_half(Vec3::ZERO, Vec3::ONE);
        assert_eq!(tree.insert(extra, 9999, 1), None);
        tree.validate().unwrap();
        assert_eq!(tree.len(), N);
        // log₂ 512 = 9; a balanced-enough tree stays well under twice that.
        assert!(tree.height() <= 18, "height {}", tree.height());
        let mut one = Vec::new();
        tree.query(&extra, 1, |u| one.push(u));
        assert!(!one.is_empty());
        // Proxy ids are node indices; remove whichever leaf holds user 0.
        let proxy = (0..AabbTree::<N>::NODES)
            .find(|&p| tree.leaf(p).is_some_and(|n| n.child2 == 0))
            .unwrap();
        assert!(tree.remove(proxy));
        assert!(tree.insert(extra, 9999, 1).is_some());
        tree.validate().unwrap();
        tree.clear();
        assert_eq!(tree.len(), 0);
        assert_eq!(answer(&tree, &extra, 1), Vec::<u32>::new());
        tree.validate().unwrap();
    }

    /// Proxies that drift (a falling grid of 512 boxes, each moving a random step of up to
    /// a third of its size every round, so most moves leave the parent's box and are
    /// reinserted below an ancestor) keep the tree as shallow as fresh insertions do, and
    /// every query still matches the brute-force answer.
    #[test]
    fn drifting_proxies_keep_the_tree_shallow() {
        const N: usize = 512;
        let mut rng = SplitMix64::new(11);
        let mut tree: AabbTree<N> = AabbTree::new();
        let mut boxes = Vec::new();
        for i in 0..N as u32 {
            let c = Vec3::new((i % 8) as f32, ((i / 8) % 8) as f32, (i / 64) as f32);
            let b = Aabb::from_center_half(c, Vec3::splat(0.6));
            boxes.push((tree.insert(b, i, 1).unwrap(), b));
        }
        for round in 0..60 {
            for (p, b) in boxes.iter_mut() {
                let d = Vec3::new(
                    rng.range(-0.2, 0.2),
                    rng.range(-0.2, 0.2),
                    rng.range(-0.4, 0.0),
                );
                *b = b.translated(d);
                assert!(tree.move_proxy(*p, *b));
            }
            tree.validate()
                .unwrap_or_else(|e| panic!("round {round}: {e}"));
            assert!(
                tree.height() <= 18,
                "round {round}: height {}",
                tree.height()
            );
            let q = random_box(&mut rng, 6.0);
            let expected: Vec<u32> = (0..N as u32)
                .filter(|&u| boxes[u as usize].1.overlaps(&q))
                .collect();
            assert_eq!(answer(&tree, &q, 1), expected, "round {round}");
        }
    }

    /// Queries with stacks too small for the tree: with a stack of 2 the height check
    /// sends the query to the linear scan of the leaves, and with that check defeated (a
    /// root that claims height 0) the pushes that do not fit scan their subtrees. Both
    /// answers are complete, each leaf once.
    #[test]
    fn small_stack_falls_back_and_stays_complete() {
        const N: usize = 64;
        let mut rng = SplitMix64::new(3);
        let mut tree: AabbTree<N> = AabbTree::new();
        let mut boxes = Vec::new();
        for i in 0..N as u32 {
            let b = random_box(&mut rng, 6.0);
            tree.insert(b, i, 1).unwrap();
            boxes.push(b);
        }
        assert!(tree.height() >= 3);
        for _ in 0..50 {
            let q = random_box(&mut rng, 6.0);
            let expected: Vec<u32> = (0..N as u32)
                .filter(|&u| boxes[u as usize].overlaps(&q))
                .collect();
            let mut got = Vec::new();
            tree.query_with_stack::<2, _>(&q, 1, &mut |u| got.push(u));
            got.sort_unstable();
            assert_eq!(got, expected, "linear scan");
            let mut lying = tree.clone();
            let root = lying.root;
            lying.node_mut(root).unwrap().height = 0;
            let mut got = Vec::new();
            lying.query_with_stack::<3, _>(&q, 1, &mut |u| got.push(u));
            let n = got.len();
            got.sort_unstable();
            got.dedup();
            assert_eq!(got.len(), n, "a leaf reported twice");
            assert_eq!(got, expected, "subtree scans");
        }
    }
}
