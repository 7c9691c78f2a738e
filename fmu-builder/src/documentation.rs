//! `documentation/index.html` of the FMU: the body's mass, flanges, reduction and its accuracy
//! against the full FE model, readable without any tool.

use crate::report::Report;
use std::fmt::Write;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

pub fn index_html(r: &Report) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{name}</title>\
<style>body{{font-family:sans-serif;max-width:60em;margin:2em auto}}table{{border-collapse:collapse}}\
td,th{{border:1px solid #bbb;padding:0.2em 0.6em;text-align:right}}th{{background:#eee}}</style></head><body>\n\
<h1>{name}: reduced flexible body</h1>\n<p>Built by fmu-builder from a {el} mesh of {nodes} nodes and {els} elements \
({dofs} DoFs after flange coupling). GUID {guid}.</p>\n",
        name = esc(&r.model_name),
        el = esc(&r.element),
        nodes = r.nodes,
        els = r.elements,
        dofs = r.dofs_constrained,
        guid = esc(&r.guid),
    );
    let c = r.center_of_mass;
    let _ = write!(
        h,
        "<h2>Rigid body</h2>\n<table><tr><th>mass [kg]</th><td>{:.6e}</td></tr><tr><th>volume [m^3]</th><td>{:.6e}</td></tr>\
<tr><th>centre of mass [m] (body frame)</th><td>{:.6e}, {:.6e}, {:.6e}</td></tr></table>\n\
<p>Body frame: origin at the mount flange's reference point, axes of the undeformed part.</p>\n",
        r.mass, r.volume, c[0], c[1], c[2]
    );
    h.push_str("<h2>Flanges</h2>\n<table><tr><th>name</th><th>role</th><th>reference point [m]</th><th>slave nodes</th></tr>\n");
    for f in &r.flanges {
        let p = f.reference_point;
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{:.6}, {:.6}, {:.6}</td><td>{}</td></tr>",
            esc(&f.name),
            esc(&f.role),
            p[0],
            p[1],
            p[2],
            f.slave_nodes
        );
    }
    h.push_str("</table>\n");
    let _ = write!(
        h,
        "<h2>Reduction</h2>\n<p>{} with {} fixed-interface normal modes and {} constraint modes: reduced order {} \
(states q, qd: {}).</p>\n",
        esc(&r.method),
        r.fixed_interface_modes,
        r.constraint_modes,
        r.order,
        2 * r.order
    );
    h.push_str("<h3>Eigenfrequencies of the mounted body</h3>\n<table><tr><th>mode</th><th>reduced [Hz]</th><th>full FE [Hz]</th><th>relative error</th></tr>\n");
    let a = &r.accuracy;
    for i in 0..a.reduced_hz.len() {
        let full = a.full_hz.get(i).map(|f| format!("{f:.6}")).unwrap_or_default();
        let err = a.relative_error.get(i).map(|e| format!("{e:.2e}")).unwrap_or_default();
        let _ = writeln!(h, "<tr><td>{}</td><td>{:.6}</td><td>{full}</td><td>{err}</td></tr>", i + 1, a.reduced_hz[i]);
    }
    h.push_str("</table>\n");
    let _ = write!(
        h,
        "<h3>Static compliance of the force flanges</h3>\n<p>Largest deviation of the reduced from the full-model \
compliance (relative to its largest entry): {:.2e}. Constraint modes make it exact up to round-off.</p>\n",
        a.compliance_max_relative_error
    );
    h.push_str("<p>The machine-readable report, with the full compliance matrices, is <code>report.json</code> beside this file.</p>\n</body></html>\n");
    h
}
