//! The public invariant checker.

use crate::node::{CHILD, Entry, entry};
use crate::octree::Octree;
use accel_core::{PrimitiveSet, Real};
use core::borrow::Borrow;

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>> Octree<'_, T, P, S> {
    /// Checks the structure's invariants:
    /// - the grids' cells tile the shared cell lists in order, and the lists'
    ///   offsets are monotone and cover the reference array;
    /// - the first grids are the parts' roots, at level 0 and linked from
    ///   nowhere; every other grid is linked from exactly one cell of a grid
    ///   before it, one level up, lies inside that cell and no deeper than
    ///   the depth limit;
    /// - every grid's reach holds its box, its primitives' bounds and its
    ///   children's reach;
    /// - every cell's references are ascending, unique, in range, and the
    ///   primitive's bounds touch the cell; a link, if any, comes last;
    /// - every primitive is referenced by some cell.
    ///
    /// # Errors
    /// A message naming the first broken invariant.
    pub fn validate(&self) -> Result<(), String> {
        let offsets = self.cells.offsets();
        let total: usize = self.nodes.iter().map(|n| n.geometry.cell_count()).sum();
        if self.parts == 0 || self.parts > self.nodes.len() {
            return Err(format!(
                "{} parts for {} grids",
                self.parts,
                self.nodes.len()
            ));
        }
        if let Some(i) = (0..self.parts).find(|&i| self.nodes[i].level != 0) {
            return Err(format!("the root of part {i} is not at level 0"));
        }
        if offsets.len() != total + 1 {
            return Err(format!("{} offsets for {total} cells", offsets.len()));
        }
        if offsets[0] != 0 || offsets[total] as usize != self.cells.reference_count() {
            return Err("offsets do not span the reference array".into());
        }
        if let Some(i) = offsets.windows(2).position(|w| w[0] > w[1]) {
            return Err(format!("offsets decrease at cell {i}"));
        }
        let set = self.primitives();
        let n = set.len();
        let mut parents = vec![0usize; self.nodes.len()];
        let mut referenced = vec![false; n];
        let mut base = 0usize;
        for (id, node) in self.nodes.iter().enumerate() {
            if node.base as usize != base {
                return Err(format!(
                    "grid {id} starts at cell {}, not {base}",
                    node.base
                ));
            }
            base += node.geometry.cell_count();
            if node.level > self.params.max_depth {
                return Err(format!("grid {id} at level {} past the limit", node.level));
            }
            let g = &node.geometry;
            if !node.reach.contains(g.bounds()) {
                return Err(format!("grid {id}: its reach does not hold its box"));
            }
            for c in 0..g.cell_count() {
                let cell_box = g.cell_bounds(g.cell_coords(c));
                let Entry { prims, child } = entry(self.cells.cell(node.cell_index(c)));
                if let Some(child) = child {
                    let Some(ch) = self.nodes.get(child) else {
                        return Err(format!("grid {id} cell {c}: link to missing grid {child}"));
                    };
                    if child <= id || ch.level != node.level + 1 {
                        return Err(format!(
                            "grid {id} (level {}) cell {c}: child {child} at level {}",
                            node.level, ch.level
                        ));
                    }
                    if !cell_box.contains(ch.geometry.bounds()) {
                        return Err(format!(
                            "grid {child} lies outside its cell {c} of grid {id}"
                        ));
                    }
                    if !node.reach.contains(&ch.reach) {
                        return Err(format!("grid {child} reaches beyond its parent {id}"));
                    }
                    parents[child] += 1;
                }
                if let Some(w) = prims.windows(2).find(|w| w[0] >= w[1]) {
                    return Err(format!(
                        "grid {id} cell {c}: references not strictly ascending at {w:?}"
                    ));
                }
                for &p in prims {
                    if p as usize >= n || p & CHILD != 0 {
                        return Err(format!(
                            "grid {id} cell {c}: reference {p} out of range ({n} primitives)"
                        ));
                    }
                    if !set.bounds(p as usize).overlaps(&cell_box) {
                        return Err(format!(
                            "grid {id} cell {c}: primitive {p} lies outside the cell"
                        ));
                    }
                    if !node.reach.contains(&set.bounds(p as usize)) {
                        return Err(format!("grid {id}: primitive {p} lies beyond its reach"));
                    }
                    referenced[p as usize] = true;
                }
            }
        }
        if let Some(child) = (self.parts..self.nodes.len()).find(|&i| parents[i] != 1) {
            return Err(format!("grid {child} is linked {} times", parents[child]));
        }
        if let Some(p) = referenced.iter().position(|&r| !r) {
            return Err(format!("primitive {p} is in no leaf"));
        }
        Ok(())
    }
}
