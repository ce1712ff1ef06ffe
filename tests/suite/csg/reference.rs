//! An independent f64 reference for CSG, for the CSG tests: a
//! description of a CSG tree that writes itself as scene TOML, plus
//! brute-force point membership and the first boundary along a ray.
//!
//! The first boundary is found without any interval logic: collect every
//! t where the line crosses any leaf's surface, then test membership of the
//! whole tree between consecutive candidates; the first candidate where
//! membership changes is the answer.

use glam::{DAffine3, DMat3, DQuat, DVec3};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Op {
    Union,
    Intersection,
    Difference,
}

/// scale, then rotate (axis, degrees), then translate: as the scene file.
#[derive(Debug, Clone, Copy, Default)]
pub struct Trs {
    pub translate: [f64; 3],
    pub rotate: Option<[f64; 4]>,
    pub scale: Option<[f64; 3]>,
}

impl Trs {
    pub fn translate(t: [f64; 3]) -> Self {
        Self {
            translate: t,
            ..Self::default()
        }
    }

    fn matrix(&self) -> DAffine3 {
        let f = |v: [f64; 3]| DVec3::from_array(v.map(f32_exact));
        let q = match self.rotate {
            Some([x, y, z, deg]) => {
                DQuat::from_axis_angle(f([x, y, z]).normalize(), f32_exact(deg).to_radians())
            }
            None => DQuat::IDENTITY,
        };
        DAffine3::from_scale_rotation_translation(
            self.scale.map_or(DVec3::ONE, f),
            q,
            f(self.translate),
        )
    }

    fn toml(&self) -> String {
        let mut parts = vec![format!("translate = {}", arr(self.translate))];
        if let Some(r) = self.rotate {
            parts.push(format!(
                "rotate = [{:?}, {:?}, {:?}, {:?}]",
                r[0], r[1], r[2], r[3]
            ));
        }
        if let Some(s) = self.scale {
            parts.push(format!("scale = {}", arr(s)));
        }
        format!("transform = {{ {} }}", parts.join(", "))
    }
}

/// Values go to strata as f32; the reference uses the same rounded values.
fn f32_exact(x: f64) -> f64 {
    x as f32 as f64
}

fn arr(v: [f64; 3]) -> String {
    format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2])
}

/// A CSG tree as the test writes it.
#[derive(Debug, Clone)]
pub enum Node {
    Sphere {
        center: [f64; 3],
        radius: f64,
        t: Trs,
    },
    /// Capped.
    Cylinder {
        base: [f64; 3],
        axis: [f64; 3],
        radius: f64,
        height: f64,
        t: Trs,
    },
    /// `mesh` = the OBJ cube [-1, 1]³ at `path`.
    Cube { path: String, t: Trs },
    Op {
        op: Op,
        a: Box<Node>,
        b: Box<Node>,
        t: Trs,
    },
}

pub fn sphere(center: [f64; 3], radius: f64) -> Node {
    Node::Sphere {
        center,
        radius,
        t: Trs::default(),
    }
}

pub fn op(op: Op, a: Node, b: Node) -> Node {
    Node::Op {
        op,
        a: Box::new(a),
        b: Box::new(b),
        t: Trs::default(),
    }
}

impl Node {
    pub fn with(mut self, trs: Trs) -> Self {
        match &mut self {
            Node::Sphere { t, .. }
            | Node::Cylinder { t, .. }
            | Node::Cube { t, .. }
            | Node::Op { t, .. } => *t = trs,
        }
        self
    }

    /// The object as an inline TOML table (one line).
    pub fn toml(&self) -> String {
        let (shape, t) = match self {
            Node::Sphere { center, radius, t } => (format!("sphere = {{ center = {}, radius = {radius:?} }}", arr(*center)), t),
            Node::Cylinder { base, axis, radius, height, t } => (
                format!(
                    "cylinder = {{ base = {}, axis = {}, radius = {radius:?}, height = {height:?}, caps = true }}",
                    arr(*base),
                    arr(*axis)
                ),
                t,
            ),
            Node::Cube { path, t } => (format!("mesh = {path:?}"), t),
            Node::Op { op, a, b, t } => (format!("csg = {}", csg_table(*op, a, b)), t),
        };
        format!("{{ {shape}, {} }}", t.toml())
    }

    /// The object as a `[[objects]]` entry.
    pub fn object(&self, extra: &str) -> String {
        let Node::Op { op, a, b, t } = self else {
            panic!("the root must be an operation")
        };
        format!(
            "[[objects]]\ncsg = {}\n{}\n{extra}\n",
            csg_table(*op, a, b),
            t.toml()
        )
    }
}

fn csg_table(op: Op, a: &Node, b: &Node) -> String {
    let name = match op {
        Op::Union => "union",
        Op::Intersection => "intersection",
        Op::Difference => "difference",
    };
    format!("{{ op = \"{name}\", a = {}, b = {} }}", a.toml(), b.toml())
}

#[derive(Debug, Clone, Copy)]
enum Kind {
    Sphere {
        center: DVec3,
        radius: f64,
    },
    /// Canonical: around +z from z = 0.
    Cylinder {
        radius: f64,
        height: f64,
    },
    Cube,
}

#[derive(Debug, Clone, Copy)]
struct Leaf {
    kind: Kind,
    /// World to object.
    inv: DAffine3,
}

#[derive(Debug, Clone)]
enum Tree {
    Leaf(usize),
    Op(Op, Box<Tree>, Box<Tree>),
}

/// The compiled reference.
#[derive(Debug, Clone)]
pub struct Reference {
    leaves: Vec<Leaf>,
    tree: Tree,
}

impl Leaf {
    fn contains(&self, p: DVec3) -> bool {
        let q = self.inv.transform_point3(p);
        match self.kind {
            Kind::Sphere { center, radius } => (q - center).length_squared() < radius * radius,
            Kind::Cylinder { radius, height } => {
                q.x * q.x + q.y * q.y < radius * radius && q.z > 0.0 && q.z < height
            }
            Kind::Cube => q.abs().max_element() < 1.0,
        }
    }

    /// Candidate ts where the line may cross the surface (a superset).
    fn candidates(&self, o: DVec3, d: DVec3, out: &mut Vec<f64>) {
        let (o, d) = (self.inv.transform_point3(o), self.inv.transform_vector3(d));
        let quadratic = |a: f64, b: f64, c: f64, out: &mut Vec<f64>| {
            let disc = b * b - 4.0 * a * c;
            if a != 0.0 && disc >= 0.0 {
                let s = disc.sqrt();
                out.extend([(-b - s) / (2.0 * a), (-b + s) / (2.0 * a)]);
            }
        };
        let slab = |k: usize, lo: f64, hi: f64, out: &mut Vec<f64>| {
            if d[k] != 0.0 {
                out.extend([(lo - o[k]) / d[k], (hi - o[k]) / d[k]]);
            }
        };
        match self.kind {
            Kind::Sphere { center, radius } => {
                let f = o - center;
                quadratic(d.dot(d), 2.0 * f.dot(d), f.dot(f) - radius * radius, out);
            }
            Kind::Cylinder { radius, height } => {
                let a = d.x * d.x + d.y * d.y;
                quadratic(
                    a,
                    2.0 * (o.x * d.x + o.y * d.y),
                    o.x * o.x + o.y * o.y - radius * radius,
                    out,
                );
                slab(2, 0.0, height, out);
            }
            Kind::Cube => (0..3).for_each(|k| slab(k, -1.0, 1.0, out)),
        }
    }
}

impl Reference {
    pub fn new(node: &Node) -> Self {
        let mut leaves = Vec::new();
        let tree = build(node, DAffine3::IDENTITY, &mut leaves);
        Self { leaves, tree }
    }

    pub fn contains(&self, p: DVec3) -> bool {
        eval(&self.tree, &|i| self.leaves[i].contains(p))
    }

    /// Every t where the line crosses some leaf's surface, sorted, with
    /// the leaf: candidates where that leaf's membership really changes.
    pub fn crossings(&self, o: DVec3, d: DVec3) -> Vec<(f64, usize)> {
        let mut out = Vec::new();
        for (i, leaf) in self.leaves.iter().enumerate() {
            let mut c = Vec::new();
            leaf.candidates(o, d, &mut c);
            for t in c {
                let e = 1e-9 * (1.0 + t.abs());
                if t.is_finite() && leaf.contains(o + (t - e) * d) != leaf.contains(o + (t + e) * d)
                {
                    out.push((t, i));
                }
            }
        }
        out.sort_by(|a, b| a.0.total_cmp(&b.0));
        out
    }

    /// The first t > tmin where membership of the whole tree changes.
    pub fn first_boundary(&self, o: DVec3, d: DVec3, tmin: f64) -> Option<f64> {
        let mut ts: Vec<f64> = self
            .crossings(o, d)
            .into_iter()
            .map(|c| c.0)
            .filter(|&t| t > tmin)
            .collect();
        ts.dedup();
        let first = *ts.first()?;
        let mut state = self.contains(o + 0.5 * (tmin + first) * d);
        for (i, &t) in ts.iter().enumerate() {
            let next = ts.get(i + 1).copied().unwrap_or(t + 1.0);
            let after = self.contains(o + 0.5 * (t + next) * d);
            if after != state {
                return Some(t);
            }
            state = after;
        }
        None
    }
}

fn eval(tree: &Tree, leaf: &dyn Fn(usize) -> bool) -> bool {
    match tree {
        Tree::Leaf(i) => leaf(*i),
        Tree::Op(op, a, b) => {
            let (a, b) = (eval(a, leaf), eval(b, leaf));
            match op {
                Op::Union => a || b,
                Op::Intersection => a && b,
                Op::Difference => a && !b,
            }
        }
    }
}

fn build(node: &Node, parent: DAffine3, leaves: &mut Vec<Leaf>) -> Tree {
    let f = |v: [f64; 3]| DVec3::from_array(v.map(f32_exact));
    let mut leaf = |kind, m: DAffine3| {
        leaves.push(Leaf {
            kind,
            inv: m.inverse(),
        });
        Tree::Leaf(leaves.len() - 1)
    };
    match node {
        Node::Sphere { center, radius, t } => leaf(
            Kind::Sphere {
                center: f(*center),
                radius: f32_exact(*radius),
            },
            parent * t.matrix(),
        ),
        Node::Cylinder {
            base,
            axis,
            radius,
            height,
            t,
        } => {
            // Any frame with z along the axis: the cylinder is round.
            let z = f(*axis).normalize();
            let x = z.any_orthonormal_vector();
            let place =
                DAffine3::from_mat3_translation(DMat3::from_cols(x, z.cross(x), z), f(*base));
            leaf(
                Kind::Cylinder {
                    radius: f32_exact(*radius),
                    height: f32_exact(*height),
                },
                parent * t.matrix() * place,
            )
        }
        Node::Cube { t, .. } => leaf(Kind::Cube, parent * t.matrix()),
        Node::Op { op, a, b, t } => {
            let m = parent * t.matrix();
            Tree::Op(
                *op,
                Box::new(build(a, m, leaves)),
                Box::new(build(b, m, leaves)),
            )
        }
    }
}
