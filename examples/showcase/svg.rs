//! Hand-written SVG for the showcase: a scene's final state seen from the side and from
//! above, and the plot of step times and awake bodies over each run.

use std::fmt::Write;

use carom::{BodyKind, Iso, Shape, Vec3};

/// One body as the pictures need it.
pub struct Body<'a> {
    pub shape: Shape<'a>,
    pub pose: Iso,
    pub kind: BodyKind,
    pub awake: bool,
}

/// A 2D view: which world axes go right and up on the page, and which points at the eye.
#[derive(Clone, Copy)]
struct View {
    name: &'static str,
    right: fn(Vec3) -> f32,
    up: fn(Vec3) -> f32,
    toward_eye: fn(Vec3) -> f32,
}

const SIDE: View = View {
    name: "side (x right, y up)",
    right: |p| p.x,
    up: |p| p.y,
    toward_eye: |p| p.z,
};
const TOP: View = View {
    name: "top (x right, z down)",
    right: |p| p.x,
    up: |p| -p.z,
    toward_eye: |p| p.y,
};

/// Side panel size in pixels (each view), and the margin around it.
const PANEL: f32 = 460.0;
const PAD: f32 = 30.0;

/// The picture of `bodies` with `contacts` (world points) marked: side view on the left,
/// top view on the right, both at one scale fitted to the dynamic bodies.
pub fn scene(title: &str, bodies: &[Body<'_>], contacts: &[Vec3]) -> String {
    // Fit the dynamic bodies (static ground and walls can be huge); fall back to all.
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for b in bodies.iter().filter(|b| b.kind != BodyKind::Static) {
        let bb = b.shape.aabb(&b.pose);
        lo = lo.min(bb.min);
        hi = hi.max(bb.max);
    }
    if lo.x > hi.x {
        (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(1.0));
    }
    lo.y = lo.y.min(0.0); // keep the ground in the side view
    let span = (hi - lo).max(Vec3::splat(0.5));
    let (lo, hi) = (lo - span * 0.08, hi + span * 0.08);

    let size = hi - lo;
    let scale = PANEL / size.x.max(size.y).max(size.z);
    let width = 2.0 * PANEL + 3.0 * PAD;
    let height = PANEL + 2.0 * PAD;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="13">"#
    );
    let _ = writeln!(s, r##"<rect width="100%" height="100%" fill="#fbfbf8"/>"##);
    let _ = writeln!(
        s,
        r#"<text x="{PAD}" y="18" font-weight="bold">{title}</text>"#
    );
    for (i, view) in [SIDE, TOP].into_iter().enumerate() {
        let x0 = PAD + i as f32 * (PANEL + PAD);
        let y0 = PAD;
        // Page coordinates of a world point: the fitted box centred in the panel.
        let (r0, r1) = ((view.right)(lo), (view.right)(hi));
        let (u0, u1) = ((view.up)(lo), (view.up)(hi));
        let (u0, u1) = (u0.min(u1), u0.max(u1));
        let cx = x0 + 0.5 * (PANEL - (r1 - r0) * scale);
        let cy = y0 + 0.5 * (PANEL - (u1 - u0) * scale);
        let page = |p: Vec3| {
            (
                cx + ((view.right)(p) - r0) * scale,
                cy + (u1 - (view.up)(p)) * scale,
            )
        };
        let _ = writeln!(
            s,
            r##"<clipPath id="c{i}"><rect x="{x0}" y="{y0}" width="{PANEL}" height="{PANEL}"/></clipPath><rect x="{x0}" y="{y0}" width="{PANEL}" height="{PANEL}" fill="white" stroke="#999"/><text x="{x0}" y="{}" fill="#555">{} — 1 m = {scale:.1} px</text><g clip-path="url(#c{i})" stroke-linejoin="round">"##,
            y0 + PANEL + 18.0,
            view.name
        );
        // Static scenery first (it would hide what is inside the walls), then painter's
        // order: the furthest from the eye first.
        let mut order: Vec<&Body<'_>> = bodies.iter().collect();
        order.sort_by(|a, b| {
            (b.kind == BodyKind::Static)
                .cmp(&(a.kind == BodyKind::Static))
                .then(
                    (view.toward_eye)(a.pose.position)
                        .total_cmp(&(view.toward_eye)(b.pose.position)),
                )
        });
        for b in order {
            body(&mut s, b, &page, scale);
        }
        for &c in contacts {
            let (x, y) = page(c);
            let _ = writeln!(
                s,
                r##"<path d="M{:.1} {:.1}l5 5m0 -5l-5 5" stroke="#d11" stroke-width="1.5"/>"##,
                x - 2.5,
                y - 2.5
            );
        }
        s.push_str("</g>\n");
    }
    let _ = writeln!(
        s,
        r##"<text x="{}" y="18" fill="#555" text-anchor="end">grey: static, orange: awake, blue: asleep, red: contact points</text></svg>"##,
        width - PAD
    );
    s
}

/// Draw one body: its core's vertices projected, then the outline of their convex hull,
/// widened by the shape's radius (spheres and capsules are a round-capped stroke).
fn body(s: &mut String, b: &Body<'_>, page: &dyn Fn(Vec3) -> (f32, f32), scale: f32) {
    let fill = match (b.kind, b.awake) {
        (BodyKind::Static, _) => "#d4d4cc",
        (_, true) => "#f0a040",
        (_, false) => "#6a9fd0",
    };
    let Some(n) = b.shape.core_vertex_count() else {
        return; // a half-space: the panel's white is its outside; nothing to draw
    };
    let points: Vec<(f32, f32)> = (0..n)
        .map(|i| page(b.pose.transform_point(b.shape.core_vertex(i))))
        .collect();
    let outline = convex_hull(points);
    let d: String = outline
        .iter()
        .enumerate()
        .map(|(i, (x, y))| format!("{}{x:.1} {y:.1}", if i == 0 { "M" } else { "L" }))
        .collect();
    let r = b.shape.radius() * scale;
    if r > 0.0 {
        // Outline first (a slightly wider dark stroke), then the body's colour.
        let _ = writeln!(
            s,
            r##"<path d="{d}Z" fill="#333" stroke="#333" stroke-width="{:.1}" stroke-linecap="round"/><path d="{d}Z" fill="{fill}" stroke="{fill}" stroke-width="{:.1}" stroke-linecap="round"/>"##,
            2.0 * r + 1.0,
            (2.0 * r - 1.0).max(0.5)
        );
    } else {
        let _ = writeln!(
            s,
            r##"<path d="{d}Z" fill="{fill}" stroke="#333" stroke-width="0.8"/>"##
        );
    }
}

/// The convex hull of page points (Andrew's monotone chain), counter-clockwise on the page.
fn convex_hull(mut p: Vec<(f32, f32)>) -> Vec<(f32, f32)> {
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: (f32, f32), a: (f32, f32), b: (f32, f32)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut hull: Vec<(f32, f32)> = Vec::with_capacity(p.len() + 1);
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &(f32, f32)>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop(); // the last point starts the other chain
    }
    hull
}

/// One scene's run for the plot: its name and, per step, (step time in ms, awake bodies).
pub struct Series<'a> {
    pub name: &'a str,
    pub steps: &'a [(f32, u32)],
}

const COLOURS: [&str; 8] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#17becf",
];

/// One panel of the plot: a log-scale y axis.
struct Panel {
    title: &'static str,
    /// The plotted value of one step's (time in ms, awake bodies).
    get: fn(&(f32, u32)) -> f32,
    /// Where the axis may have ticks; it spans those around the data.
    ticks: &'static [f32],
    label: fn(f32) -> String,
}

/// Two panels over the step number: step time (ms, log scale) and awake bodies (log
/// scale), one line per scene.
pub fn plot(series: &[Series<'_>]) -> String {
    let (w, h, left, gap) = (760.0f32, 260.0f32, 70.0f32, 60.0f32);
    let width = left + w + 150.0;
    let height = 40.0 + 2.0 * h + gap + 40.0;
    let max_steps = series
        .iter()
        .map(|s| s.steps.len())
        .max()
        .unwrap_or(1)
        .max(1) as f32;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(
        s,
        r##"<rect width="100%" height="100%" fill="white"/><text x="{left}" y="22" font-size="15" font-weight="bold">carom showcase: every step of every scene</text>"##
    );
    let panels = [
        Panel {
            title: "step time (ms, log scale)",
            get: |x| x.0.max(1e-3),
            ticks: &[0.001, 0.01, 0.1, 1.0, 10.0, 100.0, 1000.0],
            label: |t| format!("{t}"),
        },
        Panel {
            // Plotted as awake + 1, so that 0 awake has a place on a log scale.
            title: "awake bodies (log scale)",
            get: |x| x.1 as f32 + 1.0,
            ticks: &[1.0, 2.0, 11.0, 101.0, 1001.0, 10001.0],
            label: |t| format!("{}", t - 1.0),
        },
    ];
    for (
        k,
        Panel {
            title,
            get,
            ticks,
            label,
        },
    ) in panels.into_iter().enumerate()
    {
        let top = 40.0 + k as f32 * (h + gap);
        // The axis covers the ticks around the data.
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for v in series.iter().flat_map(|s| s.steps.iter().map(get)) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        let lo = ticks
            .iter()
            .rev()
            .find(|&&t| t <= lo)
            .copied()
            .unwrap_or(ticks[0])
            .log10();
        let hi = ticks
            .iter()
            .find(|&&t| t >= hi)
            .copied()
            .unwrap_or(ticks[ticks.len() - 1])
            .log10();
        let hi = if hi > lo { hi } else { lo + 1.0 };
        let y = |v: f32| top + h - (v.log10() - lo) / (hi - lo) * h;
        let x = |i: usize| left + i as f32 / max_steps * w;
        let _ = writeln!(
            s,
            r##"<text x="{left}" y="{}" font-weight="bold">{title}</text><rect x="{left}" y="{top}" width="{w}" height="{h}" fill="none" stroke="#333"/>"##,
            top - 6.0
        );
        for &t in ticks.iter().filter(|t| (lo..=hi).contains(&t.log10())) {
            let ty = y(t);
            let _ = writeln!(
                s,
                r##"<line x1="{left}" x2="{}" y1="{ty:.1}" y2="{ty:.1}" stroke="#ddd"/><text x="{}" y="{:.1}" text-anchor="end">{}</text>"##,
                left + w,
                left - 6.0,
                ty + 4.0,
                label(t)
            );
        }
        for (j, sr) in series.iter().enumerate() {
            let pts: String = sr
                .steps
                .iter()
                .enumerate()
                .map(|(i, v)| format!("{:.1},{:.1} ", x(i + 1), y(get(v))))
                .collect();
            let c = COLOURS[j % COLOURS.len()];
            let _ = writeln!(
                s,
                r#"<polyline points="{pts}" fill="none" stroke="{c}" stroke-width="1.2"/>"#
            );
            if k == 0 {
                let ly = top + 14.0 + j as f32 * 18.0;
                let _ = writeln!(
                    s,
                    r#"<line x1="{0}" x2="{1}" y1="{ly}" y2="{ly}" stroke="{c}" stroke-width="3"/><text x="{2}" y="{3}">{4}</text>"#,
                    left + w + 15.0,
                    left + w + 35.0,
                    left + w + 42.0,
                    ly + 4.0,
                    sr.name
                );
            }
        }
    }
    // The step axis, under the lower panel.
    let bottom = 40.0 + 2.0 * h + gap;
    let tick = if max_steps > 500.0 { 100 } else { 50 };
    for i in (0..=max_steps as usize).step_by(tick) {
        let tx = left + i as f32 / max_steps * w;
        let _ = writeln!(
            s,
            r#"<text x="{tx:.1}" y="{}" text-anchor="middle">{i}</text>"#,
            bottom + 16.0
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">step</text></svg>"#,
        left + w / 2.0,
        bottom + 34.0
    );
    s
}
