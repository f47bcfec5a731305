//! `vision_msgs/msg/Detection3DArray` (vision_msgs 4.x): one detection per object, with a hypothesis whose
//! score is the tracking quality and a bounding box from the mesh.

use crate::CdrError;
use crate::header::{Header, Pose};
use crate::wire::{CdrReader, CdrWriter};

/// A `vision_msgs/msg/ObjectHypothesisWithPose`.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectHypothesisWithPose {
    /// `hypothesis.class_id`.
    pub class_id: String,
    /// `hypothesis.score`.
    pub score: f64,
    /// `pose.pose`.
    pub pose: Pose,
    /// `pose.covariance`, row-major 6 x 6 over (x, y, z, rotation about x, y, z).
    pub covariance: [f64; 36],
}

/// A `vision_msgs/msg/Detection3D`.
#[derive(Debug, Clone, PartialEq)]
pub struct Detection3D {
    /// `header`.
    pub header: Header,
    /// `results`.
    pub results: Vec<ObjectHypothesisWithPose>,
    /// `bbox.center`: the box's centre and orientation.
    pub bbox_center: Pose,
    /// `bbox.size` x, y, z, metres (along the box's own axes).
    pub bbox_size: [f64; 3],
    /// `id`.
    pub id: String,
}

/// A `vision_msgs/msg/Detection3DArray`.
#[derive(Debug, Clone, PartialEq)]
pub struct Detection3DArray {
    /// `header`.
    pub header: Header,
    /// `detections`.
    pub detections: Vec<Detection3D>,
}

/// Smallest CDR size of one Detection3D: header 13, results count 4, bbox 80, id 5.
const MIN_DETECTION_BYTES: usize = 13 + 4 + 80 + 5;
/// Smallest CDR size of one hypothesis: class id 5, score 8, pose 56, covariance 288.
const MIN_HYPOTHESIS_BYTES: usize = 5 + 8 + 56 + 288;

/// Encodes a `vision_msgs/msg/Detection3DArray` into `out` (cleared first).
pub fn encode_detection3d_array(out: &mut Vec<u8>, msg: &Detection3DArray) {
    let mut w = CdrWriter::new(out);
    msg.header.write(&mut w);
    w.count(msg.detections.len());
    for d in &msg.detections {
        d.header.write(&mut w);
        w.count(d.results.len());
        for h in &d.results {
            w.string(&h.class_id);
            w.f64(h.score);
            h.pose.write(&mut w);
            w.f64s(&h.covariance);
        }
        d.bbox_center.write(&mut w);
        w.f64s(&d.bbox_size);
        w.string(&d.id);
    }
}

/// Decodes a `vision_msgs/msg/Detection3DArray`. Never panics.
pub fn decode_detection3d_array(bytes: &[u8]) -> Result<Detection3DArray, CdrError> {
    let mut r = CdrReader::new(bytes)?;
    let header = Header::read(&mut r)?;
    let n = r.count("detections", MIN_DETECTION_BYTES)?;
    let mut detections = Vec::with_capacity(n);
    for _ in 0..n {
        let header = Header::read(&mut r)?;
        let k = r.count("detections.results", MIN_HYPOTHESIS_BYTES)?;
        let mut results = Vec::with_capacity(k);
        for _ in 0..k {
            results.push(ObjectHypothesisWithPose {
                class_id: r.string("results.hypothesis.class_id")?,
                score: r.f64("results.hypothesis.score")?,
                pose: Pose::read(&mut r, "results.pose.pose")?,
                covariance: r.f64s("results.pose.covariance")?,
            });
        }
        detections.push(Detection3D {
            header,
            results,
            bbox_center: Pose::read(&mut r, "bbox.center")?,
            bbox_size: r.f64s("bbox.size")?,
            id: r.string("detections.id")?,
        });
    }
    Ok(Detection3DArray { header, detections })
}
