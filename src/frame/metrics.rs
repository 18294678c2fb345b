//! Image-quality metrics: PSNR, SSIM (luminance) and FLIP, each with an optional mask.
//!
//! All three compare what a viewer sees: colours are clamped to `[0, 1]` and sRGB-encoded first.
//! PSNR is over RGB; SSIM is Wang et al. 2004 on Rec. 709 luma with an 11 × 11 Gaussian window
//! (σ = 1.5, K1 = 0.01, K2 = 0.03); FLIP is NVIDIA's LDR-FLIP (Andersson et al. 2020) through
//! the `nv-flip` crate at its default 67 pixels per degree. A mask restricts the *average* to
//! the pixels where it is `true`; the filters still see the whole image.
//!
//! Invariants: identical images give PSNR = ∞, SSIM = 1, FLIP = 0.

use super::{FrameError, Image, Rgba, io::to_srgb8, linear_to_srgb};
use glam::Vec4;

/// The three scores of one comparison.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Scores {
    /// Peak signal-to-noise ratio in dB (∞ for identical images).
    pub psnr: f64,
    /// Mean structural similarity of luma, in `[-1, 1]` (1 for identical images).
    pub ssim: f64,
    /// Mean FLIP error in `[0, 1]` (0 for identical images).
    pub flip: f64,
}

/// A per-pixel selection of which pixels count in an average.
pub type Mask = Image<bool>;

fn same_size<A: Copy, B: Copy>(a: &Image<A>, b: &Image<B>) -> Result<(), FrameError> {
    if a.size() != b.size() {
        return Err(FrameError::SizeMismatch {
            a: a.size(),
            b: b.size(),
        });
    }
    Ok(())
}

fn check_inputs(a: &Image<Rgba>, b: &Image<Rgba>, mask: Option<&Mask>) -> Result<(), FrameError> {
    same_size(a, b)?;
    if let Some(m) = mask {
        same_size(a, m)?;
        if !m.pixels().iter().any(|&keep| keep) {
            let (w, h) = m.size();
            return Err(FrameError::InvalidSize {
                width: u64::from(w),
                height: u64::from(h),
                reason: "the mask selects no pixel: there is nothing to average",
            });
        }
    }
    Ok(())
}

fn masked_mean(values: impl Iterator<Item = f64>, mask: Option<&Mask>) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    match mask {
        Some(m) => {
            for (v, &keep) in values.zip(m.pixels()) {
                if keep {
                    sum += v;
                    n += 1;
                }
            }
        }
        None => {
            for v in values {
                sum += v;
                n += 1;
            }
        }
    }
    if n == 0 { f64::NAN } else { sum / n as f64 }
}

fn encoded(c: Vec4) -> [f64; 3] {
    [
        linear_to_srgb(c.x) as f64,
        linear_to_srgb(c.y) as f64,
        linear_to_srgb(c.z) as f64,
    ]
}

/// PSNR in dB between two colour images, over RGB, peak 1 (sRGB-encoded, clamped).
pub fn psnr(a: &Image<Rgba>, b: &Image<Rgba>, mask: Option<&Mask>) -> Result<f64, FrameError> {
    check_inputs(a, b, mask)?;
    let se = a.pixels().iter().zip(b.pixels()).map(|(&p, &q)| {
        let (p, q) = (encoded(p), encoded(q));
        (0..3).map(|i| (p[i] - q[i]).powi(2)).sum::<f64>() / 3.0
    });
    let mse = masked_mean(se, mask);
    Ok(if mse == 0.0 {
        f64::INFINITY
    } else {
        -10.0 * mse.log10()
    })
}

fn luma(c: Vec4) -> f64 {
    let [r, g, b] = encoded(c);
    0.2126 * r + 0.7152 * g + 0.0722 * b
}

/// Separable Gaussian blur with clamped borders.
fn blur(src: &[f64], w: usize, h: usize, kernel: &[f64]) -> Vec<f64> {
    let r = (kernel.len() / 2) as isize;
    let mut tmp = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut s = 0.0;
            for (k, wk) in kernel.iter().enumerate() {
                let sx = (x as isize + k as isize - r).clamp(0, w as isize - 1) as usize;
                s += wk * src[y * w + sx];
            }
            tmp[y * w + x] = s;
        }
    }
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut s = 0.0;
            for (k, wk) in kernel.iter().enumerate() {
                let sy = (y as isize + k as isize - r).clamp(0, h as isize - 1) as usize;
                s += wk * tmp[sy * w + x];
            }
            out[y * w + x] = s;
        }
    }
    out
}

/// The per-pixel SSIM map of luma.
pub fn ssim_map(a: &Image<Rgba>, b: &Image<Rgba>) -> Result<Image<f32>, FrameError> {
    same_size(a, b)?;
    const SIGMA: f64 = 1.5;
    const C1: f64 = 0.01 * 0.01;
    const C2: f64 = 0.03 * 0.03;
    let kernel: Vec<f64> = {
        let k: Vec<f64> = (-5..=5)
            .map(|i| (-(i as f64).powi(2) / (2.0 * SIGMA * SIGMA)).exp())
            .collect();
        let s: f64 = k.iter().sum();
        k.into_iter().map(|v| v / s).collect()
    };
    let (w, h) = (a.width() as usize, a.height() as usize);
    let x: Vec<f64> = a.pixels().iter().map(|&c| luma(c)).collect();
    let y: Vec<f64> = b.pixels().iter().map(|&c| luma(c)).collect();
    let xx: Vec<f64> = x.iter().map(|v| v * v).collect();
    let yy: Vec<f64> = y.iter().map(|v| v * v).collect();
    let xy: Vec<f64> = x.iter().zip(&y).map(|(p, q)| p * q).collect();
    let (mx, my) = (blur(&x, w, h, &kernel), blur(&y, w, h, &kernel));
    let (sxx, syy, sxy) = (
        blur(&xx, w, h, &kernel),
        blur(&yy, w, h, &kernel),
        blur(&xy, w, h, &kernel),
    );
    let map = (0..w * h)
        .map(|i| {
            let (mx, my) = (mx[i], my[i]);
            let vx = (sxx[i] - mx * mx).max(0.0);
            let vy = (syy[i] - my * my).max(0.0);
            let cov = sxy[i] - mx * my;
            (((2.0 * mx * my + C1) * (2.0 * cov + C2))
                / ((mx * mx + my * my + C1) * (vx + vy + C2))) as f32
        })
        .collect();
    Image::from_vec(a.width(), a.height(), map)
}

/// Mean SSIM of luma.
pub fn ssim(a: &Image<Rgba>, b: &Image<Rgba>, mask: Option<&Mask>) -> Result<f64, FrameError> {
    check_inputs(a, b, mask)?;
    let map = ssim_map(a, b)?;
    Ok(masked_mean(map.pixels().iter().map(|&v| v as f64), mask))
}

fn to_flip_rgb8(image: &Image<Rgba>) -> nv_flip::FlipImageRgb8 {
    let rgb: Vec<u8> = to_srgb8(image)
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    nv_flip::FlipImageRgb8::with_data(image.width(), image.height(), &rgb)
}

/// The per-pixel LDR-FLIP error map (`reference` first).
pub fn flip_map(reference: &Image<Rgba>, test: &Image<Rgba>) -> Result<Image<f32>, FrameError> {
    same_size(reference, test)?;
    let map = nv_flip::flip(
        to_flip_rgb8(reference),
        to_flip_rgb8(test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    Image::from_vec(reference.width(), reference.height(), map.to_vec())
}

/// Mean LDR-FLIP error (`reference` first).
pub fn flip(
    reference: &Image<Rgba>,
    test: &Image<Rgba>,
    mask: Option<&Mask>,
) -> Result<f64, FrameError> {
    check_inputs(reference, test, mask)?;
    let map = flip_map(reference, test)?;
    Ok(masked_mean(map.pixels().iter().map(|&v| v as f64), mask))
}

/// Bytes a pixel of one image costs while two images are compared: the image decoded and held
/// (16), its share of the SSIM and FLIP buffers and the heat map. Measured: comparing two
/// 2048 × 2048 PNGs peaks at 530 MB, 63 bytes a pixel of each.
pub const COMPARE_BYTES_PER_PIXEL: u64 = 64;

/// Refuses comparing the images at `paths` (the reference, the test, a mask) when together
/// they pass the memory budget, from their headers only, before any is decoded.
pub fn budget_compare(paths: &[&std::path::Path]) -> Result<(), FrameError> {
    let mut total = 0u64;
    let mut sizes = Vec::new();
    for p in paths {
        let (w, h) = super::io::image_size(p)?;
        total = total.saturating_add(crate::memory::times(
            u64::from(w) * u64::from(h),
            COMPARE_BYTES_PER_PIXEL,
        ));
        sizes.push(format!("{} ({w} × {h})", p.display()));
    }
    crate::memory::check(|| format!("comparing {}", sizes.join(" and ")), total)?;
    Ok(())
}

/// PSNR, SSIM and FLIP of `test` against `reference`; refused, naming the image and the pixel,
/// where either holds a pixel that is not a number.
pub fn compare(
    reference: &Image<Rgba>,
    test: &Image<Rgba>,
    mask: Option<&Mask>,
) -> Result<Scores, FrameError> {
    for (image, which) in [(reference, "reference"), (test, "test")] {
        if let Some(i) = image.pixels().iter().position(|p| p.is_nan()) {
            let w = image.width() as usize;
            return Err(FrameError::NotANumber {
                image: which,
                x: (i % w) as u32,
                y: (i / w) as u32,
            });
        }
    }
    Ok(Scores {
        psnr: psnr(reference, test, mask)?,
        ssim: ssim(reference, test, mask)?,
        flip: flip(reference, test, mask)?,
    })
}

/// A heat map of a `[0, 1]` error map through FLIP's magma colour ramp.
pub fn heat_map(errors: &Image<f32>) -> Image<Rgba> {
    let float =
        nv_flip::FlipImageFloat::with_data(errors.width(), errors.height(), errors.pixels());
    let rgb = float.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    let data = rgb
        .chunks_exact(3)
        .map(|p| {
            Vec4::new(
                super::srgb_to_linear(p[0] as f32 / 255.0),
                super::srgb_to_linear(p[1] as f32 / 255.0),
                super::srgb_to_linear(p[2] as f32 / 255.0),
                1.0,
            )
        })
        .collect();
    Image::from_vec(errors.width(), errors.height(), data).expect("same size as the error map")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pattern(w: u32, h: u32, seed: u32) -> Image<Rgba> {
        let data = (0..w * h)
            .map(|i| {
                let v = ((i.wrapping_mul(2_654_435_761).wrapping_add(seed)) >> 8) as f32
                    / (1u32 << 24) as f32;
                Vec4::new(v, (v * 3.0).fract(), (v * 7.0).fract(), 1.0)
            })
            .collect();
        Image::from_vec(w, h, data).unwrap()
    }

    #[test]
    fn identical_images_score_perfectly() {
        let a = pattern(40, 30, 1);
        let s = compare(&a, &a, None).unwrap();
        assert!(s.psnr.is_infinite() && s.psnr > 0.0);
        assert!((s.ssim - 1.0).abs() < 1e-9);
        assert_eq!(s.flip, 0.0);
    }

    #[test]
    fn psnr_of_a_known_offset() {
        // Encoded black vs encoded 0.1 everywhere: MSE = 0.01 → 20 dB.
        let a = Image::new(8, 8, Vec4::new(0.0, 0.0, 0.0, 1.0)).unwrap();
        let lin = crate::frame::srgb_to_linear(0.1);
        let b = Image::new(8, 8, Vec4::new(lin, lin, lin, 1.0)).unwrap();
        assert!((psnr(&a, &b, None).unwrap() - 20.0).abs() < 1e-3);
    }

    #[test]
    fn different_images_score_worse_and_mask_selects_pixels() {
        let a = pattern(40, 30, 1);
        let mut b = a.clone();
        for x in 0..20 {
            for y in 0..30 {
                b.set(x, y, Vec4::new(1.0, 0.0, 1.0, 1.0));
            }
        }
        let s = compare(&a, &b, None).unwrap();
        assert!(s.psnr < 20.0 && s.ssim < 0.9 && s.flip > 0.1, "{s:?}");
        // Masking out the changed half leaves only equal pixels in the PSNR average.
        let mask = Image::from_vec(40, 30, (0..1200).map(|i| i % 40 >= 20).collect()).unwrap();
        assert!(psnr(&a, &b, Some(&mask)).unwrap().is_infinite());
        assert!(compare(&a, &pattern(41, 30, 1), None).is_err());
    }
}
