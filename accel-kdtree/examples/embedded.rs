//! An application that keeps its scene and the kD-tree over it in one struct
//! (issue 32, item 6): `cargo run -p accel-kdtree --example embedded`.
//!
//! `KdTree::new(&mesh)` borrows the mesh, so a struct holding the mesh and
//! that tree would borrow from itself, and a function that loads the mesh
//! could not return the tree. `KdTree::shared(Arc<mesh>)` holds a reference
//! count instead (a [`SharedKdTree`], `KdTree<'static, ..>`): the struct
//! below is built in [`App::load`], returned, and queried. The grid, the
//! octree and brute force offer the same `shared` constructors.
//!
//! It also shows the version-tolerant path for vectors: the application's
//! glam (here accel-core's own, re-exported as `accel_core::glam`; any other
//! version works the same) goes in and out through `[f32; 3]` arrays.

use accel_core::glam;
use accel_core::{Accelerator, BuildError, Ray, TriangleMesh, Vec3};
use accel_kdtree::{KdTree, SharedKdTree};
use std::sync::Arc;

/// What an application keeps between frames: its mesh and the tree over it.
struct App {
    mesh: Arc<TriangleMesh<f32>>,
    tree: SharedKdTree<f32, TriangleMesh<f32>>,
}

impl App {
    /// Makes the mesh (a torus, standing in for a loaded file) and the tree
    /// over it, and returns both together.
    fn load() -> Result<Self, BuildError> {
        let mesh = accel_scenes::torus(Vec3::ZERO, 1.0, 0.25, 48, 24)
            .cast::<f32>()
            .expect("the torus fits in f32");
        let mesh = Arc::new(mesh);
        let tree = KdTree::shared(Arc::clone(&mesh))?;
        Ok(Self { mesh, tree })
    }

    /// Where a ray given in the application's glam vectors first meets the
    /// mesh, as a glam point, and which triangle it meets.
    fn pick(&self, origin: glam::Vec3, direction: glam::Vec3) -> Option<(glam::Vec3, u32)> {
        // Arrays, not `From<glam::Vec3>`: this works for any glam version.
        let ray = Ray::new(
            Vec3::from(origin.to_array()),
            Vec3::from(direction.to_array()),
        )
        .ok()?;
        let hit = self.tree.intersect(&ray).ok()??;
        Some((glam::Vec3::from_array(ray.at(hit.t).into()), hit.prim))
    }
}

fn main() -> Result<(), BuildError> {
    let app = App::load()?;
    println!(
        "{} triangles, {} kD-tree nodes; the tree's mesh is the app's: {}",
        app.mesh.triangle_count(),
        app.tree.nodes().len(),
        std::ptr::eq(app.tree.primitives(), &*app.mesh)
    );
    // From outside the ring, along +x: the tube's outer side, near x = -1.24.
    let (point, prim) = app
        .pick(glam::Vec3::new(-2.0, 0.1, 0.05), glam::Vec3::X)
        .expect("the ray meets the torus");
    println!("hit triangle {prim} at {point}");
    assert!((point.x + 1.24).abs() < 0.03, "hit at {point}");
    // Through the hole, along z: nothing.
    assert_eq!(
        app.pick(glam::Vec3::new(0.0, 0.0, -2.0), glam::Vec3::Z),
        None
    );
    println!("a ray through the hole meets nothing");
    Ok(())
}

#[cfg(test)]
mod tests {
    /// `cargo test` runs the example (`test = true` in the manifest): the
    /// app is built, returned and queried, and the hits are where they should be.
    #[test]
    fn the_app_is_built_returned_and_queried() {
        super::main().expect("the example's build");
    }
}
