//! Names the FMU's variables use besides the flanges' own: a flange named like one of them
//! (`initial`, `body`, ...) would give modelDescription.xml two variables of the same name
//! (`initial.r[1]` of a free body's start position and of the flange), which FMI forbids. The
//! list mirrors `fmu_runtime::interface::VariableTable`; a test keeps the two in step.

/// The first component of every variable name that is not a flange's (`g[1]`, `q[3]`,
/// `der(qd[1])`, `damping.alpha`, `initial.r[1]`, `frame.Q[1]`, `body.p[1]`, ...); `time` is
/// the FMI independent variable every host names so.
pub const RESERVED: [&str; 10] = ["g", "q", "qd", "der", "damping", "static_start", "time", "initial", "frame", "body"];

/// The root of a variable name: what precedes its first `.`, `[` or `(`.
pub fn root(name: &str) -> &str {
    name.split(['.', '[', '(']).next().unwrap_or(name)
}

/// Why a flange may not be called `name`, or None.
pub fn flange_name_problem(name: &str) -> Option<String> {
    RESERVED.contains(&name).then(|| {
        format!(
            "\"{name}\" is the name of the FMU's own variables ({name}...); a flange's variables would collide with them. \
             Rename the flange; reserved names: {}",
            RESERVED.join(", ")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use fmu_runtime::interface::VariableTable;
    use fmu_runtime::reduced::two_mode_body;

    /// Every variable of a mounted and of a free body is a flange's or has a reserved root.
    #[test]
    fn reserved_names_cover_the_runtime_table() {
        for free in [false, true] {
            let mut body = two_mode_body();
            body.free_floating = free;
            let flanges: Vec<String> =
                std::iter::once(body.mount.clone()).chain(body.flanges.iter().map(|f| f.name.clone())).collect();
            for v in &VariableTable::new(&body).variables {
                let r = root(&v.name);
                assert!(flanges.iter().any(|f| f == r) || RESERVED.contains(&r), "{} (free: {free})", v.name);
            }
        }
        assert!(flange_name_problem("initial").unwrap().contains("reserved"));
        assert!(flange_name_problem("tip").is_none());
    }
}
