//! What a scene that loads but would surprise is told, through the real
//! binary: a `warning:` line naming the file, the line and the key, and
//! the render going on with exit code 0.

use crate::common::scenes::LIT_SPHERE;
use crate::common::{stderr, strata};

/// Issue 62: a rect light faces edge_u × edge_v; one turned away from
/// every object lit nothing without a word. Now the render says so, at
/// the light's line, and still renders.
#[test]
fn a_light_that_reaches_nothing_is_warned_of_at_its_line() {
    let dir = crate::common::temp_dir("unreached");
    let light = |edge_u: &str, edge_v: &str| {
        format!(
            "{LIT_SPHERE}\n[[lights]]\ntype = \"rect\"\ncorner = [-0.5, 3.0, -0.5]\nedge_u = {edge_u}\nedge_v = {edge_v}\nradiance = 5.0\n"
        )
    };
    let (x, z) = ("[1.0, 0.0, 0.0]", "[0.0, 0.0, 1.0]");
    // The rect is the scene's second light, on line 14.
    std::fs::write(dir.join("up.toml"), light(z, x)).unwrap();
    let o = strata(&dir, &["render", "up.toml", "-q", "-o", "up.png"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains(
            "warning: up.toml: line 14: lights[1]: lights nothing: every object lies behind it"
        ) && e.contains("here [0, 1, 0]"),
        "{e}"
    );
    assert!(dir.join("up.png").is_file());
    // Turned round, it lights the sphere: no warning.
    std::fs::write(dir.join("down.toml"), light(x, z)).unwrap();
    let o = strata(&dir, &["render", "down.toml", "-q", "-o", "down.png"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
}
