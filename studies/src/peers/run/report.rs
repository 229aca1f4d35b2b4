//! The printed report of `studies peers`: builds, throughput, ratios to
//! the fastest Rust peer and to Embree, and the agreement of the answers.

use super::{BundleFigure, MIN_PASSES, PeersReport, SetFigure, bundle_name};
use crate::peers::EMBREE;
use render::bench::{self, Answers, RayKind};

/// The kinds measured, in order.
fn kinds_of(report: &PeersReport) -> Vec<RayKind> {
    report.ray_sets.iter().map(|(k, _)| *k).collect()
}

/// The figure of `name` on `kind`.
fn figure<'r>(report: &'r PeersReport, name: &str, kind: RayKind) -> Option<&'r SetFigure> {
    report
        .sets
        .iter()
        .find(|f| f.name == name && f.kind == kind)
}

/// The bundle sizes `name` was measured with, in order of first
/// appearance (none for a tool without packet queries).
fn bundle_sizes_of(report: &PeersReport, name: &str) -> Vec<usize> {
    let mut sizes = Vec::new();
    for f in report.sets.iter().filter(|f| f.name == name) {
        for b in &f.bundles {
            if !sizes.contains(&b.rays_per_bundle) {
                sizes.push(b.rays_per_bundle);
            }
        }
    }
    sizes
}

/// The bundle figure of `name` on `kind` in bundles of `size`.
fn bundle_figure<'r>(
    report: &'r PeersReport,
    name: &str,
    kind: RayKind,
    size: usize,
) -> Option<&'r BundleFigure> {
    figure(report, name, kind)?
        .bundles
        .iter()
        .find(|b| b.rays_per_bundle == size)
}

/// The throughput table: per tool, one row per bundle size, with the
/// single-ray figure and beside it the bundle one, per ray kind.
fn throughput_lines(report: &PeersReport, kinds: &[RayKind], out: &mut Vec<String>) {
    let mut header = format!("{:<14} {:>6}", "Mrays/s", "bundle");
    for k in kinds {
        header.push_str(&format!(" {:>9} {:>9}", k.name(), "bundled"));
    }
    out.push(header);
    for b in &report.builds {
        let sizes = bundle_sizes_of(report, &b.name);
        // A tool without bundles still gets one row, its bundles "-".
        let rows: Vec<Option<usize>> = if sizes.is_empty() {
            vec![None]
        } else {
            sizes.into_iter().map(Some).collect()
        };
        for (row, size) in rows.into_iter().enumerate() {
            let mut line = format!(
                "{:<14} {:>6}",
                b.name,
                size.map_or("-".to_owned(), |s| s.to_string())
            );
            for &k in kinds {
                let f = figure(report, &b.name, k);
                // The single-ray figure once per tool, on its first row.
                let single = match f {
                    _ if row > 0 => String::new(),
                    Some(f) => format!("{:.2}", f.mrays),
                    None => "skipped".to_owned(),
                };
                let bundled = match (f, size) {
                    (None, _) => "skipped".to_owned(),
                    (Some(_), None) => "-".to_owned(),
                    (Some(_), Some(size)) => bundle_figure(report, &b.name, k, size)
                        .map_or("-".to_owned(), |g| format!("{:.2}", g.mrays)),
                };
                line.push_str(&format!(" {single:>9} {bundled:>9}"));
            }
            out.push(line);
        }
    }
    out.push(
        "bundled: the same rays in the same order, in bundles of the size shown: ours through intersect_bundle/occluded_bundle,"
            .to_owned(),
    );
    out.push(format!(
        "  Embree through its rtcIntersect/rtcOccluded packets; camera rays by {t} x {t} tiles in Z order; -: no packet queries",
        t = bench::TILE
    ));
}

/// The ratios of ours to the peers, single rays, then ours in bundles to
/// Embree one ray at a time and in packets.
fn ratio_lines(report: &PeersReport, kinds: &[RayKind], out: &mut Vec<String>) {
    // Ratios of ours to the best Rust peer and to Embree, per kind.
    let rust_peers: Vec<&str> = crate::peers::peer_kinds()
        .iter()
        .filter(|k| k.rust)
        .map(|k| k.name)
        .collect();
    let best_rust = |k: RayKind| {
        report
            .sets
            .iter()
            .filter(|f| f.kind == k && rust_peers.contains(&f.name.as_str()))
            .max_by(|a, b| a.mrays.total_cmp(&b.mrays))
    };
    let has_rust = kinds.iter().any(|&k| best_rust(k).is_some());
    let has_embree = kinds.iter().any(|&k| figure(report, EMBREE, k).is_some());
    if has_rust || has_embree {
        out.push(String::new());
        out.push("ours / peer, one ray at a time (> 1: ours faster)".to_owned());
        let mut header = format!("{:<14}", "");
        for k in kinds {
            if has_rust {
                header.push_str(&format!(" {:>21}", format!("{} / best Rust", k.name())));
            }
            if has_embree {
                header.push_str(&format!(" {:>17}", format!("{} / Embree", k.name())));
            }
        }
        out.push(header);
        for b in report.builds.iter().filter(|b| b.ours) {
            let mut line = format!("{:<14}", b.name);
            for &k in kinds {
                let ours = figure(report, &b.name, k).map(|f| f.mrays);
                if has_rust {
                    let cell = match (ours, best_rust(k)) {
                        (Some(o), Some(p)) => format!("{:.2} ({})", o / p.mrays, p.name),
                        _ => "-".to_owned(),
                    };
                    line.push_str(&format!(" {cell:>21}"));
                }
                if has_embree {
                    let cell = match (ours, figure(report, EMBREE, k)) {
                        (Some(o), Some(e)) => format!("{:.2}", o / e.mrays),
                        _ => "-".to_owned(),
                    };
                    line.push_str(&format!(" {cell:>17}"));
                }
            }
            out.push(line);
        }
    }
    // Ours in bundles against Embree's rtcIntersect1/rtcOccluded1 and
    // against its fastest packets on the same set.
    let ours_bundled = |name: &str, k: RayKind| {
        figure(report, name, k)
            .and_then(|f| f.bundles.first())
            .map(|b| b.mrays)
    };
    let embree_packets = |k: RayKind| {
        figure(report, EMBREE, k)?
            .bundles
            .iter()
            .max_by(|a, b| a.mrays.total_cmp(&b.mrays))
    };
    let any_ours_bundled = report
        .builds
        .iter()
        .filter(|b| b.ours)
        .any(|b| kinds.iter().any(|&k| ours_bundled(&b.name, k).is_some()));
    if has_embree && any_ours_bundled {
        out.push(String::new());
        out.push(format!(
            "ours in bundles of {} / Embree one ray at a time (rtc1) and in its fastest packets (> 1: ours faster)",
            bench::BUNDLE
        ));
        let mut header = format!("{:<14}", "");
        for k in kinds {
            header.push_str(&format!(" {:>15}", format!("{} / rtc1", k.name())));
            header.push_str(&format!(" {:>18}", format!("{} / packets", k.name())));
        }
        out.push(header);
        for b in report.builds.iter().filter(|b| b.ours) {
            let mut line = format!("{:<14}", b.name);
            for &k in kinds {
                let ours = ours_bundled(&b.name, k);
                let single = match (ours, figure(report, EMBREE, k)) {
                    (Some(o), Some(e)) => format!("{:.2}", o / e.mrays),
                    _ => "-".to_owned(),
                };
                let packets = match (ours, embree_packets(k)) {
                    (Some(o), Some(p)) => format!("{:.2} (x{})", o / p.mrays, p.rays_per_bundle),
                    _ => "-".to_owned(),
                };
                line.push_str(&format!(" {single:>15} {packets:>18}"));
            }
            out.push(line);
        }
    }
}

/// The agreement table: each tool's single-ray answers against the
/// reference, then each tool's bundle answers against its own single-ray
/// ones; the first differing rays.
fn agreement_lines(report: &PeersReport, kinds: &[RayKind], out: &mut Vec<String>) {
    out.push(String::new());
    out.push(format!(
        "agreement with the reference (rays differing: hit/miss, triangle, t by > {:e} relative); bundles (x64, x16, ...) with the tool's own single rays",
        report.t_tolerance
    ));
    out.push(format!(
        "{:<18} {:<8} {:>9} {:>9} {:>17} {:>9} {:>9} {:>9}  {}",
        "tool", "rays", "count", "hits", "t sum", "hit/miss", "triangle", "t", "reference"
    ));
    let mut examples = Vec::new();
    let mut disagreeing = 0;
    let t_sum = |a: &Answers| a.t_sum.map_or("-".to_owned(), |t| format!("{t:.9e}"));
    for &k in kinds {
        for f in report.sets.iter().filter(|f| f.kind == k) {
            let rows = std::iter::once((
                f.name.clone(),
                &f.answers,
                &f.agreement,
                f.reference.clone(),
            ))
            .chain(f.bundles.iter().map(|b| {
                (
                    bundle_name(&f.name, b.rays_per_bundle),
                    &b.answers,
                    &b.agreement,
                    format!("{} single", f.name),
                )
            }));
            for (name, answers, a, reference) in rows {
                out.push(format!(
                    "{:<18} {:<8} {:>9} {:>9} {:>17} {:>9} {:>9} {:>9}  {}",
                    name,
                    k.name(),
                    a.rays,
                    answers.hits,
                    t_sum(answers),
                    a.hit_miss,
                    a.prim,
                    a.t,
                    reference
                ));
                if !a.agrees() {
                    disagreeing += 1;
                }
                examples.extend(
                    a.examples
                        .iter()
                        .map(|e| format!("  {name} {}: {e}", k.name())),
                );
            }
        }
    }
    if disagreeing == 0 {
        out.push("every tool agrees on every ray".to_owned());
    } else {
        out.push(format!(
            "{disagreeing} rows differ from their reference; first differing rays:"
        ));
        out.extend(examples);
    }
}

/// The report as printed: builds, throughput, ratios, agreement.
#[must_use]
pub fn report_lines(report: &PeersReport) -> Vec<String> {
    let kinds = kinds_of(report);
    let mut out = Vec::new();
    out.push(format!(
        "scene {}: {} triangles; one thread; Mrays/s of the median pass (>= {MIN_PASSES} passes, >= {} s per figure, a set's figures in {} interleaved rounds)",
        report.scene, report.triangles, report.min_time_s, report.rounds
    ));
    out.push(String::new());
    out.push(format!(
        "{:<14} {:>10} {:>9}  (median of {} interleaved rounds)",
        "build", "ms", "Mtris/s", report.build_rounds
    ));
    for b in &report.builds {
        out.push(format!(
            "{:<14} {:>10.1} {:>9.2}",
            b.name, b.build_ms, b.mtris_per_s
        ));
    }
    out.push(String::new());
    throughput_lines(report, &kinds, &mut out);
    ratio_lines(report, &kinds, &mut out);
    agreement_lines(report, &kinds, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::super::BuildFigure;
    use super::*;
    use crate::peers::{Agreement, T_TOLERANCE};

    fn answers(hits: u64) -> Answers {
        Answers {
            hits,
            t_sum: None,
            digest: hits,
        }
    }

    fn agreement(rays: u64, hit_miss: u64) -> Agreement {
        Agreement {
            rays,
            hit_miss,
            examples: (0..hit_miss).map(|i| format!("ray {i}: differs")).collect(),
            ..Agreement::default()
        }
    }

    fn bundle(size: usize, mrays: f64) -> BundleFigure {
        BundleFigure {
            rays_per_bundle: size,
            mrays,
            passes: 3,
            answers: answers(7),
            agreement: agreement(100, 0),
        }
    }

    fn set(name: &str, kind: RayKind, mrays: f64, bundles: Vec<BundleFigure>) -> SetFigure {
        SetFigure {
            name: name.to_owned(),
            kind,
            mrays,
            passes: 3,
            answers: answers(7),
            reference: "grid".to_owned(),
            agreement: agreement(100, 0),
            bundles,
        }
    }

    fn build(name: &str, ours: bool) -> BuildFigure {
        BuildFigure {
            name: name.to_owned(),
            ours,
            build_ms: 1.0,
            mtris_per_s: 1.0,
            rounds_ms: vec![1.0],
        }
    }

    /// Ours (grid, kdtree), a Rust peer without packets (obvhs) and Embree
    /// with packets of 16 and 8, on primary and shadow rays; Embree's
    /// 8-wide shadow packets disagree with its single rays on one ray.
    fn report() -> PeersReport {
        let (p, s) = (RayKind::Primary, RayKind::Shadow);
        let mut x8 = bundle(8, 16.0);
        x8.agreement = agreement(100, 1);
        PeersReport {
            scene: "test".to_owned(),
            triangles: 10,
            ray_source: "generated".to_owned(),
            ray_sets: vec![(p, 100), (s, 100)],
            min_time_s: 0.0,
            rounds: 1,
            t_tolerance: T_TOLERANCE,
            build_rounds: 1,
            builds: vec![
                build("grid", true),
                build("kdtree", true),
                build("obvhs", false),
                build(EMBREE, false),
            ],
            sets: vec![
                set("grid", p, 10.0, vec![bundle(64, 25.0)]),
                set("grid", s, 30.0, vec![bundle(64, 33.0)]),
                set("kdtree", p, 8.0, vec![bundle(64, 9.0)]),
                set("obvhs", p, 5.0, Vec::new()),
                set("obvhs", s, 6.0, Vec::new()),
                set(EMBREE, p, 12.5, vec![bundle(16, 20.0), bundle(8, 16.0)]),
                set(EMBREE, s, 15.0, vec![bundle(16, 22.0), x8]),
            ],
            unavailable: Vec::new(),
            failed: Vec::new(),
            skipped: vec![("kdtree".to_owned(), s, 99.0)],
        }
    }

    /// The words of the first line of `lines` that starts with the words
    /// `first`, at or after the first line that starts with `after`.
    fn row<'l>(lines: &'l [String], after: &str, first: &[&str]) -> Vec<&'l str> {
        let from = lines
            .iter()
            .position(|l| l.starts_with(after))
            .unwrap_or_else(|| panic!("no line {after:?}: {lines:#?}"));
        lines[from..]
            .iter()
            .map(|l| l.split_whitespace().collect::<Vec<_>>())
            .find(|w| w.starts_with(first))
            .unwrap_or_else(|| panic!("no line {first:?} after {after:?}: {lines:#?}"))
    }

    #[test]
    fn the_report_shows_bundles_beside_single_rays() {
        let lines = report_lines(&report());
        let table = "Mrays/s";
        assert_eq!(
            row(&lines, table, &["Mrays/s"]),
            [
                "Mrays/s", "bundle", "primary", "bundled", "shadow", "bundled"
            ]
        );
        // Tool, bundle size, then single and bundled per kind.
        assert_eq!(
            row(&lines, table, &["grid"]),
            ["grid", "64", "10.00", "25.00", "30.00", "33.00"]
        );
        assert_eq!(
            row(&lines, table, &["kdtree"]),
            ["kdtree", "64", "8.00", "9.00", "skipped", "skipped"]
        );
        // No packets: no bundle figure, not a loop's.
        assert_eq!(
            row(&lines, table, &["obvhs"]),
            ["obvhs", "-", "5.00", "-", "6.00", "-"]
        );
        // Embree: a row per packet width, the single figure once.
        let embree: Vec<_> = lines
            .iter()
            .skip_while(|l| !l.starts_with(table))
            .filter(|l| l.starts_with("embree "))
            .take(2)
            .map(|l| l.split_whitespace().collect::<Vec<_>>())
            .collect();
        assert_eq!(
            embree,
            [
                vec!["embree", "16", "12.50", "20.00", "15.00", "22.00"],
                vec!["embree", "8", "16.00", "16.00"],
            ]
        );
    }

    #[test]
    fn the_report_compares_our_bundles_with_embree_single_and_packets() {
        let lines = report_lines(&report());
        let title = "ours in bundles of 64 / Embree";
        assert_eq!(
            row(&lines, title, &["primary", "/", "rtc1"]),
            [
                "primary", "/", "rtc1", "primary", "/", "packets", "shadow", "/", "rtc1", "shadow",
                "/", "packets"
            ]
        );
        // grid: 25 / 12.5 and 25 / 20 (x16, the faster); 33 / 15 and 33 / 22.
        assert_eq!(
            row(&lines, title, &["grid"]),
            ["grid", "2.00", "1.25", "(x16)", "2.20", "1.50", "(x16)"]
        );
        assert_eq!(
            row(&lines, title, &["kdtree"]),
            ["kdtree", "0.72", "0.45", "(x16)", "-", "-"]
        );
        // The single-ray ratios stay: grid / obvhs and grid / Embree.
        let single = "ours / peer, one ray at a time";
        assert_eq!(
            row(&lines, single, &["grid"]),
            ["grid", "2.00", "(obvhs)", "0.80", "5.00", "(obvhs)", "2.00"]
        );
        // No Embree figure, no bundle ratios.
        let mut without = report();
        without.sets.retain(|f| f.name != EMBREE);
        assert!(!report_lines(&without).iter().any(|l| l.starts_with(title)));
    }

    #[test]
    fn the_report_checks_bundles_against_the_tool_s_single_rays() {
        let lines = report_lines(&report());
        let title = "agreement with the reference";
        assert_eq!(
            row(&lines, title, &["grid", "x64", "primary"]),
            [
                "grid", "x64", "primary", "100", "7", "-", "0", "0", "0", "grid", "single"
            ]
        );
        assert_eq!(
            row(&lines, title, &["embree", "x8", "shadow"]),
            [
                "embree", "x8", "shadow", "100", "7", "-", "1", "0", "0", "embree", "single"
            ]
        );
        assert!(
            lines.contains(&"1 rows differ from their reference; first differing rays:".to_owned())
        );
        assert!(lines.contains(&"  embree x8 shadow: ray 0: differs".to_owned()));
        // Without the disagreement every row agrees.
        let mut fixed = report();
        fixed.sets.last_mut().unwrap().bundles[1].agreement = agreement(100, 0);
        assert!(report_lines(&fixed).contains(&"every tool agrees on every ray".to_owned()));
    }
}
