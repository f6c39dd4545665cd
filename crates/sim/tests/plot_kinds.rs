//! Every kind of plot the commands draw, rendered to PNG and SVG by the one
//! plot module: a line plot, stacked panels with limits and notes, a
//! logarithmic frequency axis, a coded-state axis, and a histogram (values
//! binned here, and counted by the caller as `helicon mc` streams them).
//! Each PNG is checked to be a picture of the figure's size with more than
//! the background in it; the SVG to hold the labels the reader needs.
#![allow(clippy::unwrap_used)] // test helpers: a failed unwrap is a failed test

use helicon_sim::plot::{Figure, HLine, Histogram, LinePlot, Panel, Series, bin_layout, bin_of};
use std::path::Path;

/// The PNG's size (a PNG with more than a blank page's bytes in it).
fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n", "{}", path.display());
    let be = |s: &[u8]| u32::from_be_bytes([s[0], s[1], s[2], s[3]]);
    assert!(b.len() > 10_000, "{}: {} bytes", path.display(), b.len());
    (be(&b[16..20]), be(&b[20..24]))
}

/// The texts of an SVG plot, trimmed, in drawing order.
fn svg_texts(path: &Path) -> Vec<String> {
    let s = std::fs::read_to_string(path).unwrap();
    s.split("<text")
        .skip(1)
        .filter_map(|t| {
            let body = &t[t.find('>')? + 1..];
            Some(body[..body.find("</text>")?].trim().to_string())
        })
        .collect()
}

#[test]
fn every_plot_kind_renders() {
    let dir = helicon_test_support::tmpdir("plot_kinds");
    let d = dir.to_path_buf();
    let t: Vec<f64> = (0..400).map(|k| f64::from(k) * 0.05).collect();
    let sine: Vec<(f64, f64)> = t.iter().map(|t| (*t, t.sin())).collect();
    let cosine: Vec<(f64, f64)> = t.iter().map(|t| (*t, 0.5 * t.cos())).collect();
    // ψ wrapping through ±π: drawn unconnected across the wrap
    let psi: Vec<(f64, f64)> = t
        .iter()
        .map(|t| (*t, helicon_core::frames::wrap_pi(0.4 * t)))
        .collect();
    for ext in ["png", "svg"] {
        // a line plot
        let p = d.join(format!("line.{ext}"));
        LinePlot::new("line", "time [s]", "value [-]")
            .series(Series::new("sin", &sine))
            .series(Series::new("cos", &cosine).dashed())
            .write(&p)
            .unwrap();
        // stacked panels: a limit, a note, a wrapped angle, a coded state
        let mode: Vec<(f64, f64)> = t.iter().map(|t| (*t, (t / 7.0).floor())).collect();
        let mut limits = Panel::new("servo [-]").series(Series::new("S_col", &sine));
        limits.hlines.push(HLine {
            y: 0.9,
            label: "max 0.9".into(),
            color: [214, 39, 40],
        });
        limits.notes.push("min -1.5 (off scale)".into());
        let p = d.join(format!("panels.{ext}"));
        Figure::new("panels", "time [s]")
            .panel(limits)
            .panel(
                Panel::new("ψ [rad]")
                    .series(Series::new("ψ", &psi).break_jumps_over(std::f64::consts::PI)),
            )
            .panel(
                Panel::new("mode")
                    .series(Series::new("mode", &mode))
                    .categories(["idle", "spool", "fly"]),
            )
            .write(&p)
            .unwrap();
        // a frequency response on a logarithmic axis
        let w: Vec<f64> = (0..60).map(|k| 0.2 + f64::from(k) * 0.03).collect();
        let mag: Vec<(f64, f64)> = w.iter().map(|x| (*x, -20.0 * x)).collect();
        let ph: Vec<(f64, f64)> = w.iter().map(|x| (*x, -90.0 * x)).collect();
        // a band defined on the first and last 20 points only (NaN between,
        // as a confidence band over the coherent points): two lines, a gap
        let band: Vec<(f64, f64)> = mag
            .iter()
            .enumerate()
            .map(|(k, &(x, y))| {
                (
                    x,
                    if (20..40).contains(&k) {
                        f64::NAN
                    } else {
                        y + 3.0
                    },
                )
            })
            .collect();
        let p = d.join(format!("bode.{ext}"));
        Figure::new("bode", "ω [rad/s]")
            .log_x()
            .panel(
                Panel::new("magnitude [dB]")
                    .series(Series::new("estimate", &mag))
                    .series(Series::new("+2ε", &band).color([150, 150, 150]).with_gaps()),
            )
            .panel(Panel::new("phase [deg]").series(Series::new("estimate", &ph)))
            .write(&p)
            .unwrap();
        if ext == "svg" {
            let text = std::fs::read_to_string(&p).unwrap();
            let grey_lines = text
                .split("<polyline")
                .skip(1)
                .filter(|l| l.contains("#969696"))
                .count();
            // its two pieces and its legend sample (one piece without the gap)
            assert_eq!(grey_lines, 3, "the band is not broken at its gap");
            // marked in rad/s (2, 5, 10, 20, 50 on less than two decades),
            // not in log10 ω
            let texts = svg_texts(&p);
            for mark in ["2", "5", "10", "20", "50", "ω [rad/s]"] {
                assert!(
                    texts.iter().any(|t| t == mark),
                    "no {mark} on the log axis: {texts:?}"
                );
            }
        }
        // histograms: of values, and of bins counted by the caller
        let values: Vec<f64> = (0..200).map(|k| (f64::from(k) * 0.37).sin()).collect();
        let p = d.join(format!("hist.{ext}"));
        Histogram::new("values", "x [m]", &values)
            .note("200 runs flown")
            .write(&p)
            .unwrap();
        let layout = bin_layout(3, 17.8, 18.8);
        let mut counts = vec![0usize; layout.2];
        for x in [17.8, 18.0, 18.8] {
            counts[bin_of(x, layout)] += 1;
        }
        let bins: Vec<(f64, f64, usize)> = counts
            .iter()
            .enumerate()
            .map(|(b, c)| (layout.0 + b as f64 * layout.1, layout.1, *c))
            .collect();
        let p2 = d.join(format!("hist_binned.{ext}"));
        let mut h = Histogram::of_bins("settling", "settling [s]", bins)
            .note("100 runs flown")
            .note("97 not settled");
        h.y_label = "runs".into();
        h.write(&p2).unwrap();
        if ext == "svg" {
            let texts = svg_texts(&p2);
            for text in [
                "3 values",
                "97 not settled",
                "settling [s]",
                "runs",
                "0",
                "1",
                "2",
            ] {
                assert!(texts.iter().any(|t| t == text), "no `{text}` in {texts:?}");
            }
            // whole counts only on the count axis
            assert!(
                !texts.iter().any(|t| t == "0.5" || t == "1.0" || t == "1.5"),
                "fractional counts: {texts:?}"
            );
        } else {
            assert_eq!(png_size(&p2), (1000, 500));
        }
    }
    assert_eq!(png_size(&d.join("line.png")), (1000, 600));
    let (w, h) = png_size(&d.join("panels.png"));
    // three panels of 210 px under a 44 px title, over a 48 px x-axis
    assert_eq!((w, h), (1200, 44 + 3 * 210 + 48));
    png_size(&d.join("bode.png"));
    png_size(&d.join("hist.png"));
}

/// Readings drawn as points (a circle each, and one in the legend) beside
/// a fitted line; a histogram's bin width in the unit of its axis.
#[test]
fn readings_are_drawn_as_points_and_bin_widths_have_units() {
    let dir = helicon_test_support::tmpdir("plot_points");
    let fit: Vec<(f64, f64)> = (0..50)
        .map(|k| (f64::from(k) * 0.1, f64::from(k) * 0.2))
        .collect();
    let readings = [(0.5, 1.1), (2.0, 3.9), (4.5, 9.2)];
    let p = dir.join("points.svg");
    Figure::new("points", "pitch [rad]")
        .panel(
            Panel::new("thrust [N]")
                .series(Series::new("readings", &readings).markers())
                .series(Series::new("fit", &fit)),
        )
        .write(&p)
        .unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    assert_eq!(
        text.matches("<circle").count(),
        4,
        "readings not drawn as points"
    );
    png_size(&{
        let png = dir.join("points.png");
        Figure::new("points", "pitch [rad]")
            .panel(Panel::new("thrust [N]").series(Series::new("readings", &readings).markers()))
            .write(&png)
            .unwrap();
        png
    });
}
