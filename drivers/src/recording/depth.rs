//! Depth images: 16-bit grayscale PNG on disk (millimetres, 0 = invalid), `f32` metres in memory.

use std::fs::File;
use std::io::{BufReader, BufWriter};
use std::path::Path;

/// One depth frame in the depth camera's image.
#[derive(Debug, Clone, PartialEq)]
pub struct DepthFrame {
    /// Depth frame number (the 30 Hz pulse number on the trigger timeline).
    pub index: u64,
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Row-major depth along the optical axis, metres; 0 where invalid.
    pub depth_m: Vec<f32>,
}

/// Reads a 16-bit grayscale PNG as raw units. Errors say what is wrong (the caller adds the path).
pub fn read_depth_png(path: &Path) -> Result<(u32, u32, Vec<u16>), String> {
    let file = File::open(path).map_err(|e| e.to_string())?;
    let decoder = png::Decoder::new(BufReader::new(file));
    let mut reader = decoder
        .read_info()
        .map_err(|e| format!("not a readable PNG: {e}"))?;
    let info = reader.info();
    let (w, h) = (info.width, info.height);
    if info.color_type != png::ColorType::Grayscale || info.bit_depth != png::BitDepth::Sixteen {
        return Err(format!(
            "depth must be 16-bit grayscale, found {:?} at {:?} bits",
            info.color_type, info.bit_depth
        ));
    }
    let mut buf = vec![0u8; reader.output_buffer_size()];
    let frame = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("corrupt PNG data: {e}"))?;
    let bytes = &buf[..frame.buffer_size()];
    let units = bytes
        .chunks_exact(2)
        .map(|c| u16::from_be_bytes([c[0], c[1]]))
        .collect::<Vec<u16>>();
    if units.len() != (w as usize) * (h as usize) {
        return Err(format!(
            "PNG holds {} samples, expected {w}x{h}",
            units.len()
        ));
    }
    Ok((w, h, units))
}

/// Reads only the PNG header: `(width, height)`, checking it is 16-bit grayscale.
pub fn depth_png_size(path: &Path) -> Result<(u32, u32), String> {
    let file = File::open(path).map_err(|e| e.to_string())?;
    let reader = png::Decoder::new(BufReader::new(file))
        .read_info()
        .map_err(|e| format!("not a readable PNG: {e}"))?;
    let info = reader.info();
    if info.color_type != png::ColorType::Grayscale || info.bit_depth != png::BitDepth::Sixteen {
        return Err(format!(
            "depth must be 16-bit grayscale, found {:?} at {:?} bits",
            info.color_type, info.bit_depth
        ));
    }
    Ok((info.width, info.height))
}

/// Writes raw units (e.g. millimetres) as a 16-bit grayscale PNG.
pub fn write_depth_png(path: &Path, width: u32, height: u32, units: &[u16]) -> Result<(), String> {
    if units.len() != width as usize * height as usize {
        return Err(format!(
            "{} samples given for a {width}x{height} image",
            units.len()
        ));
    }
    let file = File::create(path).map_err(|e| e.to_string())?;
    let mut enc = png::Encoder::new(BufWriter::new(file), width, height);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Sixteen);
    enc.set_compression(png::Compression::Fast);
    let mut w = enc.write_header().map_err(|e| e.to_string())?;
    let bytes: Vec<u8> = units.iter().flat_map(|u| u.to_be_bytes()).collect();
    w.write_image_data(&bytes).map_err(|e| e.to_string())?;
    w.finish().map_err(|e| e.to_string())
}
