//! Pinhole camera intrinsics and regions of interest.
//!
//! Pixel convention (OpenCV): the centre of pixel `(u, v)` sits at the continuous image coordinate `(u, v)`, so pixel
//! `u` covers `[u - 0.5, u + 0.5)`. Camera frame: x right, y down, z forward, metres.

use nalgebra::{Point2, Point3};

/// Why a camera or region of interest was rejected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CameraError {
    /// A focal length or principal point is not finite, or a focal length is not positive.
    #[error(
        "invalid pinhole intrinsics: {what} = {value} (focal lengths must be finite and > 0, centres finite)"
    )]
    InvalidIntrinsics {
        /// Which parameter is wrong (`fx`, `fy`, `cx`, `cy`).
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// The image has zero width or height.
    #[error("invalid image size {width}x{height}: both must be > 0")]
    EmptyImage {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// A region of interest has a non-finite corner or a non-positive extent or output size.
    #[error("invalid region of interest: {0}")]
    InvalidRoi(String),
}

/// Pinhole intrinsics of a distortion-free camera (OpenCV convention) together with its image size.
///
/// Invariants (checked by [`PinholeCamera::new`]): `fx, fy > 0`, all parameters finite, `width, height > 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PinholeCamera {
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels (pixel-centre coordinates).
    pub cx: f64,
    /// Principal point y, pixels (pixel-centre coordinates).
    pub cy: f64,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
}

impl PinholeCamera {
    /// Builds validated intrinsics; see the type's invariants.
    pub fn new(
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        width: u32,
        height: u32,
    ) -> Result<Self, CameraError> {
        let camera = Self {
            fx,
            fy,
            cx,
            cy,
            width,
            height,
        };
        camera.validate()?;
        Ok(camera)
    }

    /// Checks the invariants (the fields are public, so a camera built by hand may violate them).
    pub fn validate(&self) -> Result<(), CameraError> {
        let Self {
            fx,
            fy,
            cx,
            cy,
            width,
            height,
        } = *self;
        for (what, value, positive) in [
            ("fx", fx, true),
            ("fy", fy, true),
            ("cx", cx, false),
            ("cy", cy, false),
        ] {
            if !value.is_finite() || (positive && value <= 0.0) {
                return Err(CameraError::InvalidIntrinsics { what, value });
            }
        }
        if width == 0 || height == 0 {
            return Err(CameraError::EmptyImage { width, height });
        }
        Ok(())
    }

    /// Intrinsics from a horizontal field of view (radians) with the principal point at the image centre and square
    /// pixels.
    pub fn from_horizontal_fov(
        hfov_rad: f64,
        width: u32,
        height: u32,
    ) -> Result<Self, CameraError> {
        let f = f64::from(width) * 0.5 / (hfov_rad * 0.5).tan();
        Self::new(
            f,
            f,
            f64::from(width) * 0.5 - 0.5,
            f64::from(height) * 0.5 - 0.5,
            width,
            height,
        )
    }

    /// Projects a point in the camera frame (metres) to pixel coordinates; `None` if it is not in front (`z <= 0`).
    /// The result may lie outside the image.
    pub fn project(&self, p: &Point3<f64>) -> Option<Point2<f64>> {
        if p.z <= 0.0 || !p.z.is_finite() {
            return None;
        }
        Some(Point2::new(
            self.fx * p.x / p.z + self.cx,
            self.fy * p.y / p.z + self.cy,
        ))
    }

    /// Back-projects pixel coordinates `(u, v)` at depth `z` (metres along the optical axis) into the camera frame.
    pub fn unproject(&self, uv: &Point2<f64>, z: f64) -> Point3<f64> {
        Point3::new(
            (uv.x - self.cx) / self.fx * z,
            (uv.y - self.cy) / self.fy * z,
            z,
        )
    }

    /// Whether pixel-centre coordinates `(u, v)` fall inside the image (`[-0.5, width - 0.5)` etc.).
    pub fn contains(&self, uv: &Point2<f64>) -> bool {
        uv.x >= -0.5
            && uv.y >= -0.5
            && uv.x < f64::from(self.width) - 0.5
            && uv.y < f64::from(self.height) - 0.5
    }

    /// The intrinsics of the virtual camera that sees exactly `roi` of this camera's image, resampled to the ROI's
    /// output size. Rendering with these intrinsics is rendering the region of interest.
    pub fn crop(&self, roi: &Roi) -> PinholeCamera {
        let sx = f64::from(roi.out_width) / roi.width;
        let sy = f64::from(roi.out_height) / roi.height;
        // Output pixel i's centre maps to full-image coordinate x0 - 0.5 + (i + 0.5) / sx.
        PinholeCamera {
            fx: self.fx * sx,
            fy: self.fy * sy,
            cx: (self.cx + 0.5 - roi.x) * sx - 0.5,
            cy: (self.cy + 0.5 - roi.y) * sy - 0.5,
            width: roi.out_width,
            height: roi.out_height,
        }
    }

    /// The whole image as a region of interest at native resolution.
    pub fn full_roi(&self) -> Roi {
        Roi {
            x: 0.0,
            y: 0.0,
            width: f64::from(self.width),
            height: f64::from(self.height),
            out_width: self.width,
            out_height: self.height,
        }
    }
}

/// A region of interest: an axis-aligned rectangle of the full image, resampled to `out_width x out_height` pixels.
///
/// The rectangle is given in pixel-edge coordinates: the full image spans `[0, width] x [0, height]`, i.e. pixel
/// `(u, v)` covers `[u, u + 1) x [v, v + 1)`. The rectangle may extend beyond the image (that part renders empty when
/// rendering, and is simply outside the sensor). Invariants (checked by [`Roi::new`]): finite corner, positive extent
/// and output size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Roi {
    /// Left edge, full-image pixels.
    pub x: f64,
    /// Top edge, full-image pixels.
    pub y: f64,
    /// Width, full-image pixels.
    pub width: f64,
    /// Height, full-image pixels.
    pub height: f64,
    /// Output width, pixels.
    pub out_width: u32,
    /// Output height, pixels.
    pub out_height: u32,
}

impl Roi {
    /// Builds a validated region of interest; see the type's invariants.
    pub fn new(
        x: f64,
        y: f64,
        width: f64,
        height: f64,
        out_width: u32,
        out_height: u32,
    ) -> Result<Self, CameraError> {
        if !(x.is_finite() && y.is_finite()) {
            return Err(CameraError::InvalidRoi(format!(
                "corner ({x}, {y}) is not finite"
            )));
        }
        if !(width.is_finite() && height.is_finite() && width > 0.0 && height > 0.0) {
            return Err(CameraError::InvalidRoi(format!(
                "extent {width}x{height} must be finite and > 0"
            )));
        }
        if out_width == 0 || out_height == 0 {
            return Err(CameraError::InvalidRoi(format!(
                "output size {out_width}x{out_height} must be > 0"
            )));
        }
        Ok(Self {
            x,
            y,
            width,
            height,
            out_width,
            out_height,
        })
    }

    /// A square region of side `side_px` (full-image pixels) centred on the pixel-centre coordinate `center`,
    /// resampled to `out_size x out_size`. This is the tracker's crop (side = 1.2 x projected diameter).
    pub fn square(center: &Point2<f64>, side_px: f64, out_size: u32) -> Result<Self, CameraError> {
        Self::new(
            center.x + 0.5 - side_px * 0.5,
            center.y + 0.5 - side_px * 0.5,
            side_px,
            side_px,
            out_size,
            out_size,
        )
    }

    /// The region covering an object of diameter `diameter_m` whose centre is at `center_cam` (camera frame, metres),
    /// enlarged by `scale` (1.2 in the tracker), resampled to `out_size x out_size`.
    pub fn around_object(
        camera: &PinholeCamera,
        center_cam: &Point3<f64>,
        diameter_m: f64,
        scale: f64,
        out_size: u32,
    ) -> Result<Self, CameraError> {
        let center = camera.project(center_cam).ok_or_else(|| {
            CameraError::InvalidRoi(format!(
                "object centre {center_cam:?} is not in front of the camera"
            ))
        })?;
        let side = scale * diameter_m * camera.fx.max(camera.fy) / center_cam.z;
        Self::square(&center, side, out_size)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> PinholeCamera {
        PinholeCamera::new(600.0, 610.0, 639.5, 359.5, 1280, 720).unwrap()
    }

    #[test]
    fn project_unproject_round_trip() {
        let c = cam();
        let p = Point3::new(0.1, -0.05, 0.7);
        let uv = c.project(&p).unwrap();
        let q = c.unproject(&uv, p.z);
        assert!((p - q).norm() < 1e-12);
        assert!(c.project(&Point3::new(0.0, 0.0, -1.0)).is_none());
    }

    #[test]
    fn rejects_bad_intrinsics() {
        assert!(matches!(
            PinholeCamera::new(0.0, 1.0, 0.0, 0.0, 10, 10),
            Err(CameraError::InvalidIntrinsics { what: "fx", .. })
        ));
        assert!(PinholeCamera::new(1.0, 1.0, f64::NAN, 0.0, 10, 10).is_err());
        assert!(PinholeCamera::new(1.0, 1.0, 0.0, 0.0, 0, 10).is_err());
        assert!(Roi::new(0.0, 0.0, -1.0, 1.0, 4, 4).is_err());
        assert!(Roi::new(0.0, 0.0, 1.0, 1.0, 0, 4).is_err());
    }

    #[test]
    fn integer_crop_shifts_principal_point() {
        let c = cam();
        let roi = Roi::new(100.0, 50.0, 160.0, 160.0, 160, 160).unwrap();
        let r = c.crop(&roi);
        assert!((r.cx - (c.cx - 100.0)).abs() < 1e-12);
        assert!((r.cy - (c.cy - 50.0)).abs() < 1e-12);
        assert_eq!(r.fx, c.fx);
        // The full ROI is the identity.
        assert_eq!(c.crop(&c.full_roi()), c);
    }

    #[test]
    fn scaled_crop_maps_pixel_centres() {
        let c = cam();
        let roi = Roi::new(300.0, 200.0, 320.0, 320.0, 160, 160).unwrap();
        let r = c.crop(&roi);
        // A point projecting to output pixel centre (i, j) projects in the full image to the centre of the
        // corresponding 2x2 block.
        let p = r.unproject(&Point2::new(10.0, 20.0), 1.0);
        let full = c.project(&p).unwrap();
        assert!((full.x - (300.0 + 2.0 * 10.0 + 0.5)).abs() < 1e-9);
        assert!((full.y - (200.0 + 2.0 * 20.0 + 0.5)).abs() < 1e-9);
    }
}
