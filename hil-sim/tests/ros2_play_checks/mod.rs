//! What `tests/ros2_play.rs` checks of the received messages against the recording.

use drivers::event::{EventBuffer, EventSink};
use drivers::formats::evt3::Evt3Decoder;
use drivers::recording::{Recording, read_depth_png};
use ros2::Attachment;

/// `header.stamp` offset the test passes, nanoseconds.
pub const OFFSET_NS: i64 = 1_700_000_000_000_000_000;
/// `--slice-us` the test passes.
pub const SLICE_US: i64 = 1000;

/// A sample as received: key, payload, attachment.
pub type Received = (String, Vec<u8>, Attachment);

/// The rising edges of the phase-coded pulses on the schedule's channel: depth frame n's exposure is the n-th.
pub fn wide_rises(rec: &Recording) -> Vec<i64> {
    let mut b = EventBuffer::new();
    rec.events().unwrap().read_all(&mut b).unwrap();
    let s = rec.meta.trigger;
    let threshold = (s.narrow_width_us + s.wide_width_us) / 2;
    let edges: Vec<_> = b
        .triggers
        .iter()
        .filter(|e| e.channel == s.channel)
        .collect();
    edges
        .windows(2)
        .filter(|w| w[0].rising && !w[1].rising && w[1].t_us - w[0].t_us >= threshold)
        .map(|w| w[0].t_us)
        .collect()
}

/// Every CD event and trigger edge's time, in stream order.
#[derive(Default)]
struct Times(Vec<i64>);

impl EventSink for Times {
    fn cd(&mut self, e: drivers::event::CdEvent) {
        self.0.push(e.t_us);
    }
    fn trigger(&mut self, e: drivers::event::TriggerEdge) {
        self.0.push(e.t_us);
    }
}

/// Checks the event packets; returns each one's latest event time.
pub fn check_event_packets(rec: &Recording, packets: &[&Received]) -> Vec<Option<i64>> {
    let raw = std::fs::read(rec.dir().join("events.raw")).unwrap();
    let body = &raw[rec.events_header.data_offset as usize..];
    let mut joined = Vec::new();
    let mut decoder = Evt3Decoder::new(None);
    let mut latest = Vec::new();
    for (i, (_, payload, att)) in packets.iter().enumerate() {
        assert_eq!(att.sequence_number, i as i64 + 1, "attachment sequence");
        let p = ros2::sensor::decode_event_packet(payload).unwrap();
        assert_eq!(p.seq, i as u64, "seq");
        assert_eq!((p.width, p.height), (1280, 720));
        assert_eq!(
            (p.encoding.as_str(), p.is_bigendian, p.time_base),
            ("evt3", false, 0)
        );
        assert_eq!(p.header.frame_id, "event_camera_optical_frame");
        assert_eq!(joined.len() % 2, 0, "packet {i} starts at an odd offset");
        joined.extend_from_slice(p.events);
        let mut times = Times::default();
        decoder.decode(p.events, &mut times);
        if let Some(&first) = times.0.first() {
            assert_eq!(
                p.header.stamp.as_nanos(),
                OFFSET_NS + 1000 * first,
                "packet {i}"
            );
            let (lo, hi) = (times.0.iter().min().unwrap(), times.0.iter().max().unwrap());
            assert!(hi - lo < SLICE_US, "packet {i} spans {lo}..{hi} us");
        }
        latest.push(times.0.iter().max().copied());
    }
    assert_eq!(
        joined, body,
        "the packets' events are events.raw after its header"
    );
    latest
}

pub fn check_depth(rec: &Recording, images: &[&Received], infos: &[&Received]) {
    let rises = wide_rises(rec);
    assert_eq!(images.len(), rec.depth_frames.len());
    assert_eq!(infos.len(), rec.depth_frames.len());
    let cam = &rec.rig.depth_camera;
    for (i, &k) in rec.depth_frames.iter().enumerate() {
        let stamp = OFFSET_NS + 1000 * rises[k as usize];
        let image = ros2::sensor::decode_image(&images[i].1).unwrap();
        assert_eq!(images[i].2.sequence_number, i as i64 + 1);
        assert_eq!(image.header.stamp.as_nanos(), stamp, "frame {k}");
        assert_eq!(image.header.frame_id, "camera_depth_optical_frame");
        assert_eq!(
            (image.width, image.height, image.step),
            (cam.width, cam.height, 2 * cam.width)
        );
        assert_eq!((image.encoding.as_str(), image.is_bigendian), ("16UC1", 0));
        let (_, _, units) = read_depth_png(&rec.depth_path(k)).unwrap();
        let pixels: Vec<u16> = image
            .data
            .chunks_exact(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]))
            .collect();
        assert_eq!(pixels, units, "frame {k} pixels");
        let frame = rec.depth_frame(k).unwrap();
        let metres: Vec<f32> = pixels.iter().map(|&u| f32::from(u) * 0.001).collect();
        assert_eq!(metres, frame.depth_m, "frame {k} in metres");
        let info = ros2::sensor::decode_camera_info(&infos[i].1).unwrap();
        assert_eq!(info.header, image.header);
        assert_eq!(
            info.k,
            [cam.fx, 0.0, cam.cx, 0.0, cam.fy, cam.cy, 0.0, 0.0, 1.0]
        );
        assert_eq!(
            info.p[..8],
            [cam.fx, 0.0, cam.cx, 0.0, 0.0, cam.fy, cam.cy, 0.0]
        );
        assert_eq!(info.d, cam.distortion);
        assert_eq!(info.distortion_model, "plumb_bob");
        assert_eq!((info.width, info.height), (cam.width, cam.height));
    }
}
