//! The sensor messages of the vendors' ROS 2 drivers: `event_camera_msgs/msg/EventPacket` (ros-event-camera's
//! `metavision_driver`), `sensor_msgs/msg/Image` and `sensor_msgs/msg/CameraInfo` (realsense-ros). Decoders borrow
//! the large byte fields from the input.

use crate::CdrError;
use crate::header::Header;
use crate::wire::{CdrReader, CdrWriter};

/// An `event_camera_msgs/msg/EventPacket`. With `encoding` `evt3` the `events` bytes are the next piece of the
/// camera's raw EVT3 word stream; `time_base` is then undefined (the stream carries its own time).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EventPacket<'a> {
    /// `header`: the host time the packet's data arrived, and the camera's frame.
    pub header: Header,
    /// `height`, pixels.
    pub height: u32,
    /// `width`, pixels.
    pub width: u32,
    /// `seq`: the packet's number, +1 per packet.
    pub seq: u64,
    /// `time_base`.
    pub time_base: u64,
    /// `encoding` (`evt3`, `mono`, `trigger`, ...).
    pub encoding: String,
    /// `is_bigendian`.
    pub is_bigendian: bool,
    /// `events`.
    pub events: &'a [u8],
}

/// Encodes an `event_camera_msgs/msg/EventPacket` into `out` (cleared first).
pub fn encode_event_packet(out: &mut Vec<u8>, p: &EventPacket<'_>) {
    let mut w = CdrWriter::new(out);
    p.header.write(&mut w);
    w.u32(p.height);
    w.u32(p.width);
    w.u64(p.seq);
    w.u64(p.time_base);
    w.string(&p.encoding);
    w.bool(p.is_bigendian);
    w.bytes(p.events);
}

/// Decodes an `event_camera_msgs/msg/EventPacket`, borrowing `events` from `bytes`. Never panics.
pub fn decode_event_packet(bytes: &[u8]) -> Result<EventPacket<'_>, CdrError> {
    let mut r = CdrReader::new(bytes)?;
    Ok(EventPacket {
        header: Header::read(&mut r)?,
        height: r.u32("height")?,
        width: r.u32("width")?,
        seq: r.u64("seq")?,
        time_base: r.u64("time_base")?,
        encoding: r.string("encoding")?,
        is_bigendian: r.bool("is_bigendian")?,
        events: r.bytes("events")?,
    })
}

/// A `sensor_msgs/msg/Image`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image<'a> {
    /// `header`: the exposure's time and the camera's optical frame.
    pub header: Header,
    /// `height`, rows.
    pub height: u32,
    /// `width`, columns.
    pub width: u32,
    /// `encoding` (`16UC1`, `32FC1`, ...).
    pub encoding: String,
    /// `is_bigendian` (a `uint8` in this message).
    pub is_bigendian: u8,
    /// `step`: bytes per row.
    pub step: u32,
    /// `data`: `step * height` bytes.
    pub data: &'a [u8],
}

/// Encodes a `sensor_msgs/msg/Image` into `out` (cleared first).
pub fn encode_image(out: &mut Vec<u8>, m: &Image<'_>) {
    let mut w = CdrWriter::new(out);
    m.header.write(&mut w);
    w.u32(m.height);
    w.u32(m.width);
    w.string(&m.encoding);
    w.u8(m.is_bigendian);
    w.u32(m.step);
    w.bytes(m.data);
}

/// Decodes a `sensor_msgs/msg/Image`, borrowing `data` from `bytes`. Never panics.
pub fn decode_image(bytes: &[u8]) -> Result<Image<'_>, CdrError> {
    let mut r = CdrReader::new(bytes)?;
    Ok(Image {
        header: Header::read(&mut r)?,
        height: r.u32("height")?,
        width: r.u32("width")?,
        encoding: r.string("encoding")?,
        is_bigendian: r.u8("is_bigendian")?,
        step: r.u32("step")?,
        data: r.bytes("data")?,
    })
}

/// A `sensor_msgs/msg/CameraInfo`.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraInfo {
    /// `header`.
    pub header: Header,
    /// `height`, pixels.
    pub height: u32,
    /// `width`, pixels.
    pub width: u32,
    /// `distortion_model` (`plumb_bob`, `rational_polynomial`, ...).
    pub distortion_model: String,
    /// `d`: distortion coefficients.
    pub d: Vec<f64>,
    /// `k`: intrinsic matrix, row-major 3 x 3 (`fx 0 cx; 0 fy cy; 0 0 1`).
    pub k: [f64; 9],
    /// `r`: rectification rotation, row-major 3 x 3.
    pub r: [f64; 9],
    /// `p`: projection matrix, row-major 3 x 4.
    pub p: [f64; 12],
    /// `binning_x`.
    pub binning_x: u32,
    /// `binning_y`.
    pub binning_y: u32,
    /// `roi`: x_offset, y_offset, height, width.
    pub roi: [u32; 4],
    /// `roi.do_rectify`.
    pub roi_do_rectify: bool,
}

/// Encodes a `sensor_msgs/msg/CameraInfo` into `out` (cleared first).
pub fn encode_camera_info(out: &mut Vec<u8>, m: &CameraInfo) {
    let mut w = CdrWriter::new(out);
    m.header.write(&mut w);
    w.u32(m.height);
    w.u32(m.width);
    w.string(&m.distortion_model);
    w.count(m.d.len());
    w.f64s(&m.d);
    w.f64s(&m.k);
    w.f64s(&m.r);
    w.f64s(&m.p);
    w.u32(m.binning_x);
    w.u32(m.binning_y);
    for v in m.roi {
        w.u32(v);
    }
    w.bool(m.roi_do_rectify);
}

/// Decodes a `sensor_msgs/msg/CameraInfo`. Never panics.
pub fn decode_camera_info(bytes: &[u8]) -> Result<CameraInfo, CdrError> {
    let mut r = CdrReader::new(bytes)?;
    Ok(CameraInfo {
        header: Header::read(&mut r)?,
        height: r.u32("height")?,
        width: r.u32("width")?,
        distortion_model: r.string("distortion_model")?,
        d: r.f64_seq("d")?,
        k: r.f64s("k")?,
        r: r.f64s("r")?,
        p: r.f64s("p")?,
        binning_x: r.u32("binning_x")?,
        binning_y: r.u32("binning_y")?,
        roi: [
            r.u32("roi.x_offset")?,
            r.u32("roi.y_offset")?,
            r.u32("roi.height")?,
            r.u32("roi.width")?,
        ],
        roi_do_rectify: r.bool("roi.do_rectify")?,
    })
}
