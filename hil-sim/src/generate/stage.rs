//! The simulated scene: the renderer with the object, hand and props registered, the trajectory, and how a
//! user's OBJ, a library object or a novel object becomes the recording's model.

use super::{GenerateConfig, GenerateError, ObjectSource};
use crate::motion::Trajectory;
use crate::objects::{self, ObjectModel};
use crate::rig::{Prop, grip, hand_mesh, surroundings};
use drivers::recording::{ContinuousSymmetry, ModelInfo};
use nalgebra::{Isometry3, Point3, Vector3};
use scene::geometry::{PinholeCamera, Roi};
use scene::mesh::{Mesh, MeshLoadOptions, Symmetry, load_obj};
use std::path::Path;
use std::sync::Arc;

/// Largest user mesh the simulated scene takes, metres across: the object moves about 0.6 m in front of the
/// camera, where a 1 m object already fills the view.
pub const MAX_OBJECT_DIAMETER_M: f64 = 1.0;
use scene::render::{
    BackgroundMesh, CpuRenderer, Lighting, MeshId, RenderError, RenderTarget, Renderer, Scene,
    SceneObject,
};

/// Mask id of the hand holding object `k` (occluders, not tracked); objects take ids `1..=n`.
const HAND_ID_BASE: u16 = 1000;

/// One moving object of the scene and the hand that holds it.
pub(super) struct StageObject {
    pub(super) mesh: MeshId,
    /// Its trajectory, placed by `offset` (camera frame).
    pub(super) trajectory: Trajectory,
    pub(super) offset: Isometry3<f64>,
    /// Mesh vertices (object frame): a mesh's projected extremes are among its projected vertices.
    pub(super) points: Vec<Point3<f64>>,
    pub(super) half_extent: Vector3<f64>,
}

impl StageObject {
    /// `T_cam_obj` at `t_s` seconds.
    pub(super) fn pose(&self, t_s: f64) -> Isometry3<f64> {
        self.offset * self.trajectory.pose(t_s)
    }
}

/// The scene being simulated: renderer with every mesh registered, the moving objects and the props.
pub(super) struct Stage {
    pub(super) renderer: CpuRenderer,
    pub(super) objects: Vec<StageObject>,
    pub(super) hand: MeshId,
    pub(super) props: Vec<(MeshId, Isometry3<f64>)>,
    pub(super) hands: bool,
    pub(super) hand_points: Vec<Point3<f64>>,
}

impl Stage {
    /// Each object's pose at `t_s` (in `frame`) with the pose of the hand holding it, if one does.
    fn moving(
        &self,
        t_s: f64,
    ) -> impl Iterator<Item = (Isometry3<f64>, Option<Isometry3<f64>>)> + '_ {
        self.objects.iter().map(move |o| {
            let pose = o.pose(t_s);
            let hand = self
                .hands
                .then(|| o.trajectory.holding_hand(t_s))
                .flatten()
                .map(|side| pose * grip(side, o.half_extent));
            (pose, hand)
        })
    }

    pub(super) fn instances(
        &self,
        t_s: f64,
        frame: &Isometry3<f64>,
        with_props: bool,
    ) -> (Vec<SceneObject>, Vec<BackgroundMesh>) {
        let mut objects = Vec::with_capacity(2 * self.objects.len());
        for (k, (o, (pose, hand))) in self.objects.iter().zip(self.moving(t_s)).enumerate() {
            objects.push(SceneObject {
                mesh: o.mesh,
                pose: frame * pose,
                id: k as u16 + 1,
            });
            if let Some(hand) = hand {
                objects.push(SceneObject {
                    mesh: self.hand,
                    pose: frame * hand,
                    id: HAND_ID_BASE + k as u16,
                });
            }
        }
        let background = self
            .props
            .iter()
            .filter(|_| with_props)
            .map(|(m, p)| BackgroundMesh {
                mesh: *m,
                pose: frame * p,
            })
            .collect();
        (objects, background)
    }

    /// Renders the scene at `t_s` (the props too when `with_props`; otherwise only the moving meshes, for
    /// compositing over the cached static background, which always lies behind them).
    pub(super) fn render(
        &mut self,
        t_s: f64,
        frame: &Isometry3<f64>,
        camera: &PinholeCamera,
        roi: Option<&Roi>,
        target: &mut RenderTarget,
        with_props: bool,
    ) -> Result<(), RenderError> {
        let (objects, background) = self.instances(t_s, frame, with_props);
        let scene = Scene {
            lighting: Lighting::default(),
            ..Scene::objects(&objects).with_background(&background)
        };
        match roi {
            Some(r) => self.renderer.render_roi(&scene, camera, r, target),
            None => self.renderer.render(&scene, camera, target),
        }
    }

    /// Vertices of every moving mesh (objects and hands).
    pub(super) fn point_count(&self) -> usize {
        self.objects
            .iter()
            .map(|o| o.points.len() + self.hand_points.len())
            .sum()
    }

    /// Projects every `stride`-th vertex of the moving meshes at `t_s` into `out` (`false` if one is behind the
    /// camera).
    pub(super) fn project(
        &self,
        t_s: f64,
        camera: &PinholeCamera,
        stride: usize,
        out: &mut Vec<(f64, f64)>,
    ) -> bool {
        out.clear();
        for (o, (pose, hand)) in self.objects.iter().zip(self.moving(t_s)) {
            let sets = [(Some(pose), &o.points), (hand, &self.hand_points)];
            for (p, points) in sets {
                let Some(p) = p else { continue };
                for q in points.iter().step_by(stride.max(1)) {
                    match camera.project(&(p * q)) {
                        Some(uv) => out.push((uv.x, uv.y)),
                        None => return false,
                    }
                }
            }
        }
        true
    }
}

fn model_info(name: &str, mesh: &Mesh, symmetries: &[Symmetry]) -> ModelInfo {
    let b = mesh.aabb();
    let mut discrete = Vec::new();
    let mut continuous = Vec::new();
    for s in symmetries {
        match s {
            Symmetry::Discrete(t) => {
                let m = t.to_homogeneous();
                let mut a = [0.0; 16];
                for r in 0..4 {
                    for c in 0..4 {
                        a[r * 4 + c] = m[(r, c)];
                    }
                }
                discrete.push(a);
            }
            Symmetry::Continuous { axis, offset } => continuous.push(ContinuousSymmetry {
                axis: [axis.x, axis.y, axis.z],
                offset_m: [offset.x, offset.y, offset.z],
            }),
        }
    }
    ModelInfo {
        name: name.to_string(),
        diameter_m: mesh.diameter(),
        min_m: [b.min.x, b.min.y, b.min.z],
        size_m: [b.max.x - b.min.x, b.max.y - b.min.y, b.max.z - b.min.z],
        symmetries_discrete: discrete,
        symmetries_continuous: continuous,
    }
}

/// Copies a user OBJ with the MTL files it names and the textures those name (relative paths kept).
pub(super) fn copy_user_obj(obj: &Path, models: &Path, name: &str) -> Result<(), GenerateError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |error| GenerateError::Io { path, error }
    };
    let dir = obj.parent().unwrap_or(Path::new("."));
    let text = std::fs::read_to_string(obj).map_err(io(obj))?;
    std::fs::write(models.join(format!("{name}.obj")), &text).map_err(io(obj))?;
    let mut files: Vec<String> = Vec::new();
    for line in text.lines() {
        if let Some(rest) = line.trim().strip_prefix("mtllib ") {
            for mtl in rest.split_whitespace() {
                files.push(mtl.to_string());
                if let Ok(m) = std::fs::read_to_string(dir.join(mtl)) {
                    for l in m.lines() {
                        let l = l.trim();
                        if l.starts_with("map_")
                            && let Some(tex) = l.split_whitespace().last()
                        {
                            files.push(tex.to_string());
                        }
                    }
                }
            }
        }
    }
    for f in files {
        let (src, dst) = (dir.join(&f), models.join(&f));
        if let Some(parent) = dst.parent() {
            std::fs::create_dir_all(parent).map_err(io(parent))?;
        }
        std::fs::copy(&src, &dst).map_err(io(&src))?;
    }
    Ok(())
}

/// One object of a configuration: its name, model information and, for a generated (library or novel) object,
/// what to write.
pub(super) struct BuiltObject {
    pub(super) name: String,
    pub(super) info: ModelInfo,
    pub(super) source: ObjectSource,
    pub(super) generated: Option<Box<dyn ObjectModel>>,
}

/// The scene of a configuration, ready to render.
pub(super) struct Built {
    pub(super) stage: Stage,
    /// In scene order (the first object, then the companions).
    pub(super) objects: Vec<BuiltObject>,
}

/// The seed of the `k`-th object's trajectory and library object's texture (0: the configuration's own).
fn object_seed(seed: u64, k: usize) -> u64 {
    if k == 0 {
        seed
    } else {
        seed ^ (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
    }
}

/// An object's name, mesh, symmetries and, when generated here, the model to write.
type ObjectMesh = (String, Mesh, Vec<Symmetry>, Option<Box<dyn ObjectModel>>);

fn object_mesh(source: &ObjectSource, seed: u64) -> Result<ObjectMesh, GenerateError> {
    Ok(match source {
        ObjectSource::Library(kind) => {
            let o = objects::generate(*kind, seed);
            let mesh = o.to_mesh()?;
            (
                kind.name().to_string(),
                mesh,
                o.symmetries.clone(),
                Some(Box::new(o)),
            )
        }
        // A novel object is its family and own seed, whatever the recording's seed.
        ObjectSource::Novel {
            family,
            seed: shape_seed,
        } => {
            let o = objects::novel::generate(*family, *shape_seed);
            let mesh = ObjectModel::to_mesh(&o)?;
            (
                o.name.clone(),
                mesh,
                o.symmetries.clone(),
                Some(Box::new(o)),
            )
        }
        ObjectSource::File(path) => {
            let loaded = load_obj(path, &MeshLoadOptions::default())?;
            let diameter = loaded.mesh.diameter();
            if diameter > MAX_OBJECT_DIAMETER_M {
                return Err(GenerateError::Parameter(format!(
                    "mesh {} has a diameter of {diameter:.2} m; the simulated scene holds objects up to {} m \
                     across in front of a camera 0.6 m away (metres are expected: is it in millimetres?)",
                    path.display(),
                    MAX_OBJECT_DIAMETER_M
                )));
            }
            for w in &loaded.warnings {
                eprintln!("warning: {w}");
            }
            let stem = path
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("object");
            let name: String = stem
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                        c
                    } else {
                        '_'
                    }
                })
                .collect();
            (name, loaded.mesh, vec![], None)
        }
    })
}

pub(super) fn build(config: &GenerateConfig) -> Result<Built, GenerateError> {
    let points = |m: &Mesh| {
        m.positions()
            .iter()
            .map(|p| p.cast::<f64>())
            .collect::<Vec<Point3<f64>>>()
    };
    let mut renderer = CpuRenderer::new();
    let scene_objects = std::iter::once((
        &config.object,
        config.motion,
        config.speed,
        Vector3::zeros(),
    ))
    .chain(
        config
            .companions
            .iter()
            .map(|c| (&c.object, c.motion, c.speed, Vector3::from(c.offset_m))),
    );
    let mut stage_objects = Vec::new();
    let mut built_objects: Vec<BuiltObject> = Vec::new();
    for (k, (source, motion, speed, offset)) in scene_objects.enumerate() {
        let seed = object_seed(config.seed, k);
        let (name, mesh, symmetries, generated) = object_mesh(source, seed)?;
        if built_objects.iter().any(|b| b.name == name) {
            return Err(GenerateError::Parameter(format!(
                "two objects named `{name}`: the objects of a recording need distinct names"
            )));
        }
        let info = model_info(&name, &mesh, &symmetries);
        let b = mesh.aabb();
        stage_objects.push(StageObject {
            points: points(&mesh),
            half_extent: (b.max - b.min) / 2.0,
            mesh: renderer.add_mesh(Arc::new(mesh))?,
            trajectory: Trajectory::new(motion, speed, seed),
            offset: Isometry3::translation(offset.x, offset.y, offset.z),
        });
        built_objects.push(BuiltObject {
            name,
            info,
            source: source.clone(),
            generated,
        });
    }
    let hand = hand_mesh(config.seed)?;
    let hand_points = points(&hand);
    let hand = renderer.add_mesh(Arc::new(hand))?;
    let mut props = Vec::new();
    for Prop { mesh, pose } in surroundings(config.seed)? {
        props.push((renderer.add_mesh(mesh)?, pose));
    }
    let stage = Stage {
        renderer,
        objects: stage_objects,
        hand,
        props,
        hands: config.hands,
        hand_points,
    };
    Ok(Built {
        stage,
        objects: built_objects,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::{MotionProfile, SpeedLevel};
    use crate::objects::NovelFamily;

    #[test]
    fn a_novel_object_is_named_after_its_family_and_seed_whatever_the_recording_seed() {
        let object = ObjectSource::Novel {
            family: NovelFamily::Torus,
            seed: 4,
        };
        let built: Vec<_> = [1, 2]
            .into_iter()
            .map(|seed| {
                let config = GenerateConfig::new(
                    object.clone(),
                    MotionProfile::Shake,
                    SpeedLevel::Fast,
                    1.0,
                    seed,
                );
                build(&config).unwrap()
            })
            .collect();
        for b in &built {
            let o = &b.objects[0];
            assert_eq!(o.name, "novel_torus_4");
            assert_eq!(o.info.name, o.name);
            // A whole torus: any turn about z and a half turn about x.
            assert_eq!(o.info.symmetries_continuous.len(), 1);
            assert_eq!(o.info.symmetries_discrete.len(), 1);
            assert_eq!(
                o.generated.as_ref().map(|g| g.name()),
                Some("novel_torus_4")
            );
        }
        let points = |b: &Built| b.stage.objects[0].points.clone();
        assert_eq!(points(&built[0]), points(&built[1]));
    }
}
