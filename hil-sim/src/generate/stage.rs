//! The simulated scene: the renderer with the object, hand and props registered, the trajectory, and how a
//! user's OBJ or a library object becomes the recording's model.

use super::{GenerateConfig, GenerateError, ObjectSource};
use crate::motion::Trajectory;
use crate::objects;
use crate::rig::{Prop, grip, hand_mesh, surroundings};
use drivers::recording::{ContinuousSymmetry, ModelInfo};
use nalgebra::{Isometry3, Point3, Vector3};
use std::path::Path;
use std::sync::Arc;
use tracker::geometry::{PinholeCamera, Roi};
use tracker::mesh::{Mesh, MeshLoadOptions, Symmetry, load_obj};
use tracker::render::{
    BackgroundMesh, CpuRenderer, Lighting, MeshId, RenderError, RenderTarget, Renderer, Scene,
    SceneObject,
};

/// Mask id of the tracked object.
const OBJECT_ID: u16 = 1;
/// Mask id of the hand (an occluder, not tracked).
const HAND_ID: u16 = 2;

/// The scene being simulated: renderer with every mesh registered, the trajectory and the props.
pub(super) struct Stage {
    pub(super) renderer: CpuRenderer,
    pub(super) object: MeshId,
    pub(super) hand: MeshId,
    pub(super) props: Vec<(MeshId, Isometry3<f64>)>,
    pub(super) trajectory: Trajectory,
    pub(super) hands: bool,
    /// Mesh vertices (object frame): a mesh's projected extremes are among its projected vertices.
    pub(super) object_points: Vec<Point3<f64>>,
    pub(super) hand_points: Vec<Point3<f64>>,
    pub(super) half_extent: Vector3<f64>,
}

impl Stage {
    pub(super) fn instances(
        &self,
        t_s: f64,
        frame: &Isometry3<f64>,
        with_props: bool,
    ) -> (Vec<SceneObject>, Vec<BackgroundMesh>) {
        let pose = self.trajectory.pose(t_s);
        let mut objects = vec![SceneObject {
            mesh: self.object,
            pose: frame * pose,
            id: OBJECT_ID,
        }];
        if let Some(side) = self
            .hands
            .then(|| self.trajectory.holding_hand(t_s))
            .flatten()
        {
            objects.push(SceneObject {
                mesh: self.hand,
                pose: frame * pose * grip(side, self.half_extent),
                id: HAND_ID,
            });
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
        let pose = self.trajectory.pose(t_s);
        let hand = self
            .hands
            .then(|| self.trajectory.holding_hand(t_s))
            .flatten();
        let hand_pose = hand.map(|side| pose * grip(side, self.half_extent));
        let sets = [
            (Some(pose), &self.object_points),
            (hand_pose, &self.hand_points),
        ];
        for (p, points) in sets {
            let Some(p) = p else { continue };
            for q in points.iter().step_by(stride.max(1)) {
                match camera.project(&(p * q)) {
                    Some(uv) => out.push((uv.x, uv.y)),
                    None => return false,
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

/// The scene of a configuration, ready to render.
pub(super) struct Built {
    pub(super) stage: Stage,
    pub(super) name: String,
    pub(super) info: ModelInfo,
    pub(super) library_object: Option<objects::ProceduralObject>,
}

pub(super) fn build(config: &GenerateConfig) -> Result<Built, GenerateError> {
    let (name, mesh, symmetries, library_object) = match &config.object {
        ObjectSource::Library(kind) => {
            let o = objects::generate(*kind, config.seed);
            let mesh = o.to_mesh()?;
            (kind.name().to_string(), mesh, o.symmetries.clone(), Some(o))
        }
        ObjectSource::File(path) => {
            let loaded = load_obj(path, &MeshLoadOptions::default())?;
            for w in &loaded.warnings {
                eprintln!("warning: {}: {w}", path.display());
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
    };
    let info = model_info(&name, &mesh, &symmetries);
    let object_box = mesh.aabb();
    let hand = hand_mesh(config.seed)?;
    let points = |m: &Mesh| {
        m.positions()
            .iter()
            .map(|p| p.cast::<f64>())
            .collect::<Vec<Point3<f64>>>()
    };
    let (object_points, hand_points) = (points(&mesh), points(&hand));
    let mut renderer = CpuRenderer::new();
    let object = renderer.add_mesh(Arc::new(mesh))?;
    let hand = renderer.add_mesh(Arc::new(hand))?;
    let mut props = Vec::new();
    for Prop { mesh, pose } in surroundings(config.seed)? {
        props.push((renderer.add_mesh(mesh)?, pose));
    }
    let trajectory = Trajectory::new(config.motion, config.speed, config.seed);
    let half_extent = (object_box.max - object_box.min) / 2.0;
    let stage = Stage {
        renderer,
        object,
        hand,
        props,
        trajectory,
        hands: config.hands,
        object_points,
        hand_points,
        half_extent,
    };

    Ok(Built {
        stage,
        name,
        info,
        library_object,
    })
}
