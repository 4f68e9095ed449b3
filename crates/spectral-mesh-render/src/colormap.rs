//! Colour maps from a normalised scalar `t` in `[0, 1]` to 8-bit RGB.
//!
//! | name        | `t = 0`                 | `t = 1`                         | definition |
//! |-------------|-------------------------|---------------------------------|------------|
//! | `hue`       | red (hue 0°)            | magenta (hue 300°)              | HSV with S = V = 1 and hue = 300° · t: red, yellow, green, cyan, blue, magenta. The paper's map runs on "back to red"; we stop at 300° so that the two ends stay distinct. |
//! | `viridis`   | dark purple `#440154`   | yellow `#fde725`                | degree-6 polynomial fit of matplotlib's viridis (per channel) |
//! | `turbo`     | dark blue               | dark red                        | Google's published degree-5 polynomial approximation of Turbo |
//! | `diverging` | blue (59, 76, 192)      | red (180, 4, 38)                | piecewise linear through white at `t = 0.5` |
//! | `grey`      | black                   | white                           | linear |
//!
//! Values of `t` outside `[0, 1]` are clamped; NaN maps like `t = 0`.

use std::fmt;
use std::str::FromStr;

/// A colour map. See the [module documentation](self) for the exact definitions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Colormap {
    /// HSV hue from red (`t = 0`) through yellow, green, cyan, blue to magenta (`t = 1`,
    /// hue 300°), full saturation and value: the paper's colouring.
    #[default]
    Hue,
    /// Perceptually uniform dark purple → blue → green → yellow.
    Viridis,
    /// Rainbow-like dark blue → cyan → green → yellow → red → dark red.
    Turbo,
    /// Blue → white → red; meant for signed fields with the range symmetric about 0.
    Diverging,
    /// Black → white.
    Grey,
}

/// Error for an unknown colour-map name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown colour map '{0}' (expected one of: hue, viridis, turbo, diverging, grey)")]
pub struct UnknownColormap(pub String);

impl Colormap {
    /// Every colour map, in documentation order.
    pub const ALL: [Colormap; 5] = [
        Colormap::Hue,
        Colormap::Viridis,
        Colormap::Turbo,
        Colormap::Diverging,
        Colormap::Grey,
    ];

    /// The name accepted by [`FromStr`].
    pub fn name(self) -> &'static str {
        match self {
            Colormap::Hue => "hue",
            Colormap::Viridis => "viridis",
            Colormap::Turbo => "turbo",
            Colormap::Diverging => "diverging",
            Colormap::Grey => "grey",
        }
    }

    /// Whether the map is meant for a range symmetric about zero (only `Diverging`).
    pub fn is_diverging(self) -> bool {
        matches!(self, Colormap::Diverging)
    }

    /// Colour of `t` (clamped to `[0, 1]`) as floating-point RGB in `[0, 1]`.
    pub fn map_f32(self, t: f64) -> [f32; 3] {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        let c = match self {
            Colormap::Hue => hsv_to_rgb(300.0 * t, 1.0, 1.0),
            Colormap::Viridis => polynomial_rgb(&VIRIDIS, t),
            Colormap::Turbo => polynomial_rgb(&TURBO, t),
            Colormap::Diverging => diverging(t),
            Colormap::Grey => [t, t, t],
        };
        [
            c[0].clamp(0.0, 1.0) as f32,
            c[1].clamp(0.0, 1.0) as f32,
            c[2].clamp(0.0, 1.0) as f32,
        ]
    }

    /// Colour of `t` (clamped to `[0, 1]`) as 8-bit RGB.
    pub fn map(self, t: f64) -> [u8; 3] {
        let c = self.map_f32(t);
        [to_u8(c[0]), to_u8(c[1]), to_u8(c[2])]
    }
}

/// Rounds a channel in `[0, 1]` to 8 bits.
pub(crate) fn to_u8(c: f32) -> u8 {
    (c.clamp(0.0, 1.0) * 255.0).round() as u8
}

impl fmt::Display for Colormap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Colormap {
    type Err = UnknownColormap;

    /// Parses `hue | viridis | turbo | diverging | grey` (case-insensitive; `gray` and
    /// `hsv` are accepted as aliases).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let low = s.trim().to_ascii_lowercase();
        let alias = match low.as_str() {
            "hsv" => Some(Colormap::Hue),
            "gray" => Some(Colormap::Grey),
            _ => None,
        };
        Colormap::ALL
            .into_iter()
            .find(|c| c.name() == low)
            .or(alias)
            .ok_or_else(|| UnknownColormap(s.to_string()))
    }
}

/// HSV to RGB, hue in degrees, `s` and `v` in `[0, 1]`.
pub fn hsv_to_rgb(h_deg: f64, s: f64, v: f64) -> [f64; 3] {
    let h = h_deg.rem_euclid(360.0) / 60.0;
    let c = v * s;
    let x = c * (1.0 - ((h % 2.0) - 1.0).abs());
    let m = v - c;
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    [r + m, g + m, b + m]
}

/// A colour map whose channels are polynomials in `t`: `c[channel]` holds the
/// coefficients from the constant term up, evaluated by Horner's rule.
fn polynomial_rgb<const N: usize>(c: &[[f64; N]; 3], t: f64) -> [f64; 3] {
    c.map(|channel| channel.iter().rev().fold(0.0, |acc, &k| acc * t + k))
}

/// Viridis: per-channel (R, G, B) degree-6 polynomials for [`polynomial_rgb`].
const VIRIDIS: [[f64; 7]; 3] = [
    [
        0.277_727_327_223_417_7,
        0.105_093_043_108_577_4,
        -0.330_861_828_725_556_3,
        -4.634_230_498_983_486,
        6.228_269_936_347_081,
        4.776_384_997_670_288,
        -5.435_455_855_934_631,
    ],
    [
        0.005_407_344_544_966_578,
        1.404_613_529_898_575,
        0.214_847_559_468_213,
        -5.799_100_973_351_585,
        14.179_933_366_805_09,
        -13.745_145_377_746_01,
        4.645_852_612_178_535,
    ],
    [
        0.334_099_805_335_306_1,
        1.384_590_162_594_685,
        0.095_095_163_028_236_59,
        -19.332_440_956_279_87,
        56.690_552_600_681_05,
        -65.353_032_633_372_34,
        26.312_435_249_583_2,
    ],
];

/// Turbo: per-channel (R, G, B) degree-5 polynomials for [`polynomial_rgb`].
const TURBO: [[f64; 6]; 3] = [
    [
        0.135_721_38,
        4.615_392_60,
        -42.660_322_58,
        132.131_082_34,
        -152.942_393_96,
        59.286_379_43,
    ],
    [
        0.091_402_61,
        2.194_188_39,
        4.842_966_58,
        -14.185_033_33,
        4.277_298_57,
        2.829_566_04,
    ],
    [
        0.106_673_30,
        12.641_946_08,
        -60.582_048_36,
        110.362_767_71,
        -89.903_109_12,
        27.348_249_73,
    ],
];

/// Blue (59, 76, 192) → white → red (180, 4, 38).
fn diverging(t: f64) -> [f64; 3] {
    const BLUE: [f64; 3] = [59.0 / 255.0, 76.0 / 255.0, 192.0 / 255.0];
    const RED: [f64; 3] = [180.0 / 255.0, 4.0 / 255.0, 38.0 / 255.0];
    let (a, b, s) = if t < 0.5 {
        (BLUE, [1.0; 3], t / 0.5)
    } else {
        ([1.0; 3], RED, (t - 0.5) / 0.5)
    };
    [
        a[0] + s * (b[0] - a[0]),
        a[1] + s * (b[1] - a[1]),
        a[2] + s * (b[2] - a[2]),
    ]
}

/// A colour per label: hues spaced by the golden ratio, alternating saturation and value so
/// that neighbouring labels stay distinguishable (segmentations).
pub fn label_colors(labels: &[usize]) -> Vec<[f32; 3]> {
    const GOLDEN: f64 = 0.618_033_988_749_895;
    labels
        .iter()
        .map(|&l| {
            let h = (l as f64 * GOLDEN).fract() * 360.0;
            let v = if (l / 7) % 2 == 0 { 0.95 } else { 0.7 };
            let s = if l % 2 == 0 { 0.75 } else { 0.55 };
            hsv_to_rgb(h, s, v).map(|c| c as f32)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hex(h: u32) -> [u8; 3] {
        [(h >> 16) as u8, (h >> 8) as u8, h as u8]
    }

    fn close(a: [u8; 3], b: [u8; 3], tol: i32) -> bool {
        (0..3).all(|i| (a[i] as i32 - b[i] as i32).abs() <= tol)
    }

    /// Hue goes red, yellow, green, cyan, blue, magenta; diverging blue, white, red; grey
    /// black to white: exact colours at evenly spaced `t` from 0 to 1.
    #[test]
    fn exact_colours_at_evenly_spaced_points() {
        use Colormap::{Diverging, Grey, Hue};
        let samples: [(Colormap, &[u32]); 3] = [
            (
                Hue,
                &[0xff0000, 0xffff00, 0x00ff00, 0x00ffff, 0x0000ff, 0xff00ff],
            ),
            (Diverging, &[0x3b4cc0, 0xffffff, 0xb40426]),
            (Grey, &[0x000000, 0x808080, 0xffffff]),
        ];
        for (m, colours) in samples {
            for (i, &h) in colours.iter().enumerate() {
                let t = i as f64 / (colours.len() - 1) as f64;
                assert_eq!(m.map(t), hex(h), "{m} at {t}");
            }
        }
    }

    #[test]
    fn hue_clamps_out_of_range_and_nan() {
        let m = Colormap::Hue;
        assert_eq!(m.map(-3.0), m.map(0.0));
        assert_eq!(m.map(7.0), m.map(1.0));
        assert_eq!(m.map(f64::NAN), m.map(0.0));
    }

    #[test]
    fn viridis_matches_published_samples() {
        // matplotlib's viridis sampled at 10 evenly spaced points.
        let anchors = [
            0x440154, 0x482878, 0x3e4989, 0x31688e, 0x26828e, 0x1f9e89, 0x35b779, 0x6ece58,
            0xb5de2b, 0xfde725,
        ];
        for (i, &h) in anchors.iter().enumerate() {
            let t = i as f64 / 9.0;
            let got = Colormap::Viridis.map(t);
            assert!(close(got, hex(h), 6), "t {t}: {got:?} vs {:?}", hex(h));
        }
    }

    #[test]
    fn turbo_shape() {
        let m = Colormap::Turbo;
        let lo = m.map(0.0);
        let mid = m.map(0.5);
        let hi = m.map(1.0);
        // Dark start, bright green-yellow middle, dark red end.
        assert!(lo.iter().all(|&c| c < 60));
        assert!(mid[1] > 200);
        assert!(hi[0] > 100 && hi[1] < 40 && hi[2] < 40);
        // Blue peaks before green, green before red.
        let peak = |c: usize| {
            (0..=100)
                .max_by_key(|&i| m.map(i as f64 / 100.0)[c])
                .unwrap_or(0)
        };
        assert!(peak(2) < peak(1) && peak(1) < peak(0));
    }

    #[test]
    fn names_round_trip() {
        for m in Colormap::ALL {
            assert_eq!(m.name().parse::<Colormap>(), Ok(m));
            assert_eq!(m.to_string(), m.name());
        }
        assert_eq!("GRAY".parse::<Colormap>(), Ok(Colormap::Grey));
        assert!("jet".parse::<Colormap>().is_err());
    }
}
