//! The lattice of a picture's samples: traced at a few pixels, interpolated where the picture
//! is smooth, refined where it is not, and the jittered pattern of the anti-aliased pixels.

use super::*;

/// The samples of a `w` × `h` picture: `eval` at the pixels of a lattice every `s` pixels (and
/// the last row and column), then each block between four of them interpolated bilinearly when
/// its corners cross the same structure and its middle pixel, traced, agrees with the
/// interpolation within [`SMOOTH_MIDDLE`]; else split into four at traced side and middle
/// pixels, recursively, down to single pixels. Every decision depends only on pixels traced
/// for the block itself: the picture is the same for any number of threads.
pub(super) fn blocks(
    w: usize,
    h: usize,
    s: usize,
    eval: &(dyn Fn(usize, usize, &mut Scratch) -> Sample + Sync),
) -> Vec<Sample> {
    let mut out = vec![Sample::EMPTY; w * h];
    if s <= 1 || w < 2 || h < 2 {
        out.par_chunks_mut(w).enumerate().for_each(|(py, row)| {
            let mut scratch = Scratch::default();
            for (px, v) in row.iter_mut().enumerate() {
                *v = eval(px, py, &mut scratch);
            }
        });
        return out;
    }
    let stops = |len: usize| -> Vec<usize> {
        let mut v: Vec<usize> = (0..len).step_by(s).collect();
        if *v.last().unwrap() != len - 1 {
            v.push(len - 1);
        }
        v
    };
    let (xs, ys) = (stops(w), stops(h));
    let lattice: Vec<Sample> = ys
        .par_iter()
        .flat_map_iter(|&py| {
            let mut scratch = Scratch::default();
            let xs = &xs;
            xs.iter()
                .map(move |&px| eval(px, py, &mut scratch))
                .collect::<Vec<_>>()
        })
        .collect();
    let at = |i: usize, j: usize| lattice[j * xs.len() + i];
    // One band of blocks (rows ys[j] .. ys[j + 1], the last with its closing row) per unit of
    // parallel work.
    let mut bands: Vec<(usize, &mut [Sample])> = Vec::with_capacity(ys.len());
    let mut rest = &mut out[..];
    for j in 0..ys.len() - 1 {
        let rows = if j + 2 == ys.len() {
            h - ys[j]
        } else {
            ys[j + 1] - ys[j]
        };
        let (a, b) = std::mem::take(&mut rest).split_at_mut(rows * w);
        bands.push((j, a));
        rest = b;
    }
    bands.into_par_iter().for_each(|(j, rows)| {
        let mut scratch = Scratch::default();
        let y0 = ys[j];
        let nrows = rows.len() / w;
        let mut put = |px: usize, py: usize, v: Sample| rows[(py - y0) * w + px] = v;
        for i in 0..xs.len() - 1 {
            let corners = [at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)];
            let own = [
                if i + 2 == xs.len() {
                    xs[i + 1] + 1
                } else {
                    xs[i + 1]
                },
                y0 + nrows,
            ];
            block(
                [xs[i], xs[i + 1]],
                [y0, ys[j + 1]],
                corners,
                own,
                eval,
                &mut scratch,
                &mut put,
            );
        }
    });
    out
}

/// One block of [`blocks`] (corners x0 y0, x1 y0, x0 y1, x1 y1), putting its pixels below `own`
/// (exclusive ends).
pub(super) fn block(
    x: [usize; 2],
    y: [usize; 2],
    c: [Sample; 4],
    own: [usize; 2],
    eval: &(dyn Fn(usize, usize, &mut Scratch) -> Sample + Sync),
    scratch: &mut Scratch,
    put: &mut impl FnMut(usize, usize, Sample),
) {
    let ([x0, x1], [y0, y1]) = (x, y);
    let (xm, ym) = ((x0 + x1) / 2, (y0 + y1) / 2);
    if xm == x0 && ym == y0 {
        for (k, (px, py)) in [(x0, y0), (x1, y0), (x0, y1), (x1, y1)]
            .into_iter()
            .enumerate()
        {
            if px < own[0] && py < own[1] {
                put(px, py, c[k]);
            }
        }
        return;
    }
    let fraction = |v: usize, a: usize, b: usize| {
        if b > a {
            (v - a) as f32 / (b - a) as f32
        } else {
            0.0
        }
    };
    let mid = eval(xm, ym, scratch);
    let same = c.iter().all(|q| q.sig == mid.sig);
    if same {
        let guess = bilinear(&c, fraction(xm, x0, x1), fraction(ym, y0, y1));
        let (a, b) = (perceptual(&mid.rgba), perceptual(&guess.rgba));
        if (0..4).all(|k| (a[k] - b[k]).abs() <= SMOOTH_MIDDLE) {
            for py in y0..own[1].min(y1 + 1) {
                let fy = fraction(py, y0, y1);
                for px in x0..own[0].min(x1 + 1) {
                    put(px, py, bilinear(&c, fraction(px, x0, x1), fy));
                }
            }
            return;
        }
    }
    let top = eval(xm, y0, scratch);
    let bottom = eval(xm, y1, scratch);
    let left = eval(x0, ym, scratch);
    let right = eval(x1, ym, scratch);
    let quarters = [
        ([x0, xm], [y0, ym], [c[0], top, left, mid]),
        ([xm, x1], [y0, ym], [top, c[1], mid, right]),
        ([x0, xm], [ym, y1], [left, mid, c[2], bottom]),
        ([xm, x1], [ym, y1], [mid, right, bottom, c[3]]),
    ];
    for (qx, qy, corners) in quarters {
        let own_q = [
            if qx[1] == x1 { own[0] } else { qx[1] },
            if qy[1] == y1 { own[1] } else { qy[1] },
        ];
        if qx[0] >= own_q[0] || qy[0] >= own_q[1] {
            continue;
        }
        block(qx, qy, corners, own_q, eval, scratch, put);
    }
}

/// Bilinear interpolation of four samples (x0 y0, x1 y0, x0 y1, x1 y1) at (fx, fy); the
/// half-opacity distance where all four are finite.
pub(super) fn bilinear(c: &[Sample; 4], fx: f32, fy: f32) -> Sample {
    let w = [
        (1.0 - fx) * (1.0 - fy),
        fx * (1.0 - fy),
        (1.0 - fx) * fy,
        fx * fy,
    ];
    let rgba = std::array::from_fn(|k| {
        w[0] * c[0].rgba[k] + w[1] * c[1].rgba[k] + w[2] * c[2].rgba[k] + w[3] * c[3].rgba[k]
    });
    let half = if c.iter().all(|q| q.half.is_finite()) {
        w[0] * c[0].half + w[1] * c[1].half + w[2] * c[2].half + w[3] * c[3].half
    } else {
        f32::INFINITY
    };
    let cover = w[0] * c[0].cover + w[1] * c[1].cover + w[2] * c[2].cover + w[3] * c[3].cover;
    Sample {
        rgba,
        half,
        sig: c[0].sig,
        cover,
    }
}

/// Whether pixel (px, py) of `first` differs from one of its four neighbours: in what its ray
/// crossed, or by more than [`EDGE_STEP`] in a channel.
pub(super) fn edge_pixel(first: &[Sample], w: usize, h: usize, px: usize, py: usize) -> bool {
    let here = &first[py * w + px];
    let a = perceptual(&here.rgba);
    let differs = |q: &Sample| {
        if q.sig != here.sig {
            return true;
        }
        let b = perceptual(&q.rgba);
        (0..4).any(|k| (a[k] - b[k]).abs() > EDGE_STEP)
    };
    (px > 0 && differs(&first[py * w + px - 1]))
        || (px + 1 < w && differs(&first[py * w + px + 1]))
        || (py > 0 && differs(&first[(py - 1) * w + px]))
        || (py + 1 < h && differs(&first[(py + 1) * w + px]))
}

/// Colour as √RGB (about perceived lightness), alpha as it is.
#[inline]
pub(super) fn perceptual(v: &[f32; 4]) -> [f32; 4] {
    [
        v[0].max(0.0).sqrt(),
        v[1].max(0.0).sqrt(),
        v[2].max(0.0).sqrt(),
        v[3],
    ]
}

/// The k × k jittered sample offsets within pixel (px, py) (in [0, 1)²), the jitter a hash of
/// the pixel and the stratum: the same for any number of threads.
pub(super) fn pattern(px: usize, py: usize, k: usize) -> impl Iterator<Item = (f64, f64)> {
    (0..k * k).map(move |i| {
        let (a, b) = (i % k, i / k);
        let mut hsh = (px as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (py as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
            ^ (i as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
        hsh ^= hsh >> 29;
        hsh = hsh.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        hsh ^= hsh >> 32;
        let jx = (hsh & 0xffff) as f64 / 65536.0;
        let jy = ((hsh >> 16) & 0xffff) as f64 / 65536.0;
        ((a as f64 + jx) / k as f64, (b as f64 + jy) / k as f64)
    })
}
