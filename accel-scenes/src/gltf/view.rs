//! The camera a loaded scene is seen through: the file's first camera where
//! it is usable, else one framing the scene from the front, right and above
//! (glTF is y-up). `render` and the profiling examples ([`crate::TraceDriver`])
//! take the same view, so their rays are the same.

use super::{Scene, SceneCamera};
use crate::{Camera, Y_UP};
use accel_core::Vec3;

/// The direction a scene without a usable camera is framed from.
const FRAMED_FROM: Vec3<f64> = Vec3::new(0.55, 0.45, 1.0);

impl SceneCamera {
    /// The camera this file camera describes, or why it cannot be used (a
    /// degenerate transform, an orthographic projection, a field of view
    /// outside `(0, π)`).
    ///
    /// # Errors
    /// The reason, in words.
    pub fn camera(&self) -> Result<Camera, &'static str> {
        let finite = self.eye.is_finite() && self.forward.is_finite() && self.up.is_finite();
        if !finite || self.forward.length_squared() == 0.0 {
            return Err("its transform is degenerate");
        }
        let Some(yfov) = self.yfov else {
            return Err("it is orthographic");
        };
        if !(yfov > 0.0 && yfov < core::f64::consts::PI) {
            return Err("its field of view is out of range");
        }
        Ok(Camera::look_at(
            self.eye,
            self.eye + self.forward,
            self.up,
            yfov.to_degrees(),
        ))
    }
}

impl Scene {
    /// The camera the scene is seen through, and a note saying which it is
    /// (the file's first camera, or framed automatically and why).
    #[must_use]
    pub fn view(&self) -> (Camera, String) {
        let framed = || Camera::frame(&self.mesh.bounds(), FRAMED_FROM, Y_UP);
        match self.cameras.first().map(SceneCamera::camera) {
            Some(Ok(camera)) => (camera, "camera: the file's first camera".to_owned()),
            Some(Err(why)) => (
                framed(),
                format!(
                    "camera: framed automatically (the file's first camera is unusable: {why})"
                ),
            ),
            None => (
                framed(),
                "camera: framed automatically (the file has none)".to_owned(),
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::TriangleMesh;

    fn scene(cameras: Vec<SceneCamera>) -> Scene {
        let mesh = TriangleMesh::new(
            vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2]],
        )
        .unwrap();
        Scene { mesh, cameras }
    }

    fn looking_down(yfov: Option<f64>) -> SceneCamera {
        SceneCamera {
            eye: Vec3::new(0.2, 0.2, 5.0),
            forward: Vec3::new(0.0, 0.0, -1.0),
            up: Vec3::new(0.0, 1.0, 0.0),
            yfov,
            aspect_ratio: None,
        }
    }

    #[test]
    fn a_usable_first_camera_is_the_view_and_others_are_framed_with_the_reason() {
        let (camera, note) = scene(vec![looking_down(Some(0.8))]).view();
        assert!(note.contains("the file's first camera"), "{note}");
        // The centre pixel's ray leaves the eye along the camera's forward.
        let centre: accel_core::Ray<f64> = camera.ray_through(50.0, 50.0, 100, 100);
        assert_eq!(centre.origin, Vec3::new(0.2, 0.2, 5.0));
        let d = centre.direction.normalized();
        assert!(d.dot(Vec3::new(0.0, 0.0, -1.0)) > 0.999, "{d:?}");

        let (_, note) = scene(vec![looking_down(None)]).view();
        assert!(note.contains("unusable: it is orthographic"), "{note}");
        let (_, note) = scene(vec![looking_down(Some(4.0))]).view();
        assert!(note.contains("field of view is out of range"), "{note}");
        let mut flat = looking_down(Some(0.8));
        flat.forward = Vec3::new(0.0, 0.0, 0.0);
        let (_, note) = scene(vec![flat]).view();
        assert!(note.contains("degenerate"), "{note}");
        let (framed, note) = scene(Vec::new()).view();
        assert!(note.contains("the file has none"), "{note}");
        assert_eq!(
            framed,
            Camera::frame(&scene(Vec::new()).mesh.bounds(), FRAMED_FROM, Y_UP)
        );
    }
}
