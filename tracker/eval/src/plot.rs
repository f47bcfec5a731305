//! Simple line plots drawn with `image` (no text): error over time, one colour per method.

use image::{Rgb, RgbImage};

/// Line colours, in method order (blue, orange, green, red, purple, brown, pink, grey).
pub const PALETTE: [[u8; 3]; 8] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
];

/// Draws series of `(x, y)` points (x seconds, y any unit; non-finite y drawn at the top edge) as polylines on a
/// white `width` x `height` image with a light grid (10 divisions per axis) and black axes. The axes span
/// `x_range` and `0..=y_max`.
pub fn line_plot(
    series: &[Vec<(f64, f64)>],
    width: u32,
    height: u32,
    x_range: (f64, f64),
    y_max: f64,
) -> RgbImage {
    let mut img = RgbImage::from_pixel(width, height, Rgb([255, 255, 255]));
    let (m, w, h) = (20.0, width as f64 - 40.0, height as f64 - 40.0);
    for k in 0..=10 {
        let gx = (m + w * k as f64 / 10.0) as u32;
        let gy = (m + h * k as f64 / 10.0) as u32;
        let grid = if k == 0 {
            Rgb([0, 0, 0])
        } else {
            Rgb([225, 225, 225])
        };
        for y in m as u32..=(m + h) as u32 {
            img.put_pixel(gx.min(width - 1), y.min(height - 1), grid);
        }
        let grid = if k == 10 {
            Rgb([0, 0, 0])
        } else {
            Rgb([225, 225, 225])
        };
        for x in m as u32..=(m + w) as u32 {
            img.put_pixel(x.min(width - 1), gy.min(height - 1), grid);
        }
    }
    let span = (x_range.1 - x_range.0).max(1e-12);
    let to_px = |(x, y): (f64, f64)| {
        let y = if y.is_finite() {
            y.clamp(0.0, y_max)
        } else {
            y_max
        };
        let px = m + w * (x - x_range.0) / span;
        let py = m + h * (1.0 - y / y_max.max(1e-12));
        (px, py)
    };
    for (i, s) in series.iter().enumerate() {
        let c = Rgb(PALETTE[i % PALETTE.len()]);
        for pair in s.windows(2) {
            let (a, b) = (to_px(pair[0]), to_px(pair[1]));
            let n = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).max(1);
            for k in 0..=n {
                let t = k as f64 / n as f64;
                let (x, y) = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
                if x >= 0.0 && y >= 0.0 && (x as u32) < width && (y as u32) < height {
                    img.put_pixel(x as u32, y as u32, c);
                }
            }
        }
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_lines_in_palette_colours() {
        let img = line_plot(
            &[vec![(0.0, 0.0), (1.0, 1.0)], vec![(0.0, 0.5), (1.0, 0.5)]],
            120,
            80,
            (0.0, 1.0),
            1.0,
        );
        assert_eq!(img.dimensions(), (120, 80));
        // The horizontal line at y = 0.5 runs through the middle row.
        assert_eq!(*img.get_pixel(60, 40), Rgb(PALETTE[1]));
        // The diagonal reaches the top-right corner of the plot area.
        assert_eq!(*img.get_pixel(100, 20), Rgb(PALETTE[0]));
    }
}
