//! The pose CSV file sink: every estimate as a row of the tracker output CSV
//! (`t_us,object,x,y,z,qx,qy,qz,qw,quality,state`, [`tracker::recording::POSE_CSV_HEADER`]), numbers at full precision
//! (Rust's shortest round-trip formatting) so readers get the published `f64` values back exactly. The estimates
//! the tracker revises after publishing them (tracked again from a late depth frame) go, in the same format, to
//! a second file beside it, `<name>.revised.csv`, created at the first revision.

use super::{PoseSink, PublishError, SinkCounters, TickPoses};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use tracker::recording::{POSE_CSV_HEADER, PoseRow};

/// Writes poses to a CSV file through a buffer (no allocation per tick).
#[derive(Debug)]
pub struct CsvPoseSink {
    name: String,
    path: PathBuf,
    out: BufWriter<File>,
    counters: SinkCounters,
    /// The revised estimates' file, once one came; the object names of the rows.
    revised: Option<BufWriter<File>>,
    objects: Vec<String>,
    /// Whether a revised estimate could not be written (warned once; each one counts as failed).
    revision_failed: bool,
}

impl CsvPoseSink {
    /// Creates (truncates) `path` and writes the header line.
    pub fn create(path: &Path) -> Result<Self, PublishError> {
        let name = format!("csv:{}", path.display());
        let err = |e: std::io::Error| PublishError::Transport {
            sink: name.clone(),
            message: format!("cannot write {}: {e}", path.display()),
        };
        let file = File::create(path).map_err(err)?;
        // A previous run's revisions do not belong to this run's poses.
        let revised = Self::revised_path(path);
        match std::fs::remove_file(&revised) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => {
                return Err(PublishError::Transport {
                    sink: name.clone(),
                    message: format!("cannot remove the previous {}: {e}", revised.display()),
                });
            }
        }
        let mut out = BufWriter::with_capacity(64 * 1024, file);
        writeln!(out, "{POSE_CSV_HEADER}").map_err(err)?;
        Ok(Self {
            name: name.clone(),
            path: path.to_path_buf(),
            out,
            counters: SinkCounters::default(),
            revised: None,
            objects: Vec::new(),
            revision_failed: false,
        })
    }

    /// The file of revised estimates beside `poses`: `poses.csv` -> `poses.revised.csv`.
    pub fn revised_path(poses: &Path) -> PathBuf {
        let stem = poses
            .file_stem()
            .map_or_else(|| "poses".into(), |s| s.to_string_lossy().into_owned());
        poses.with_file_name(format!("{stem}.revised.csv"))
    }

    fn write_revised(&mut self, revised: &[tracker::track::PoseEstimate]) -> std::io::Result<()> {
        let out = match &mut self.revised {
            Some(out) => out,
            None => {
                let file = File::create(Self::revised_path(&self.path))?;
                let mut out = BufWriter::with_capacity(16 * 1024, file);
                writeln!(out, "{POSE_CSV_HEADER}")?;
                self.revised.insert(out)
            }
        };
        for e in revised {
            writeln!(out, "{}", pose_row(e, &self.objects))?;
        }
        Ok(())
    }

    /// The file written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn io_error(&self, e: std::io::Error) -> PublishError {
        PublishError::Transport {
            sink: self.name.clone(),
            message: format!("cannot write {}: {e}", self.path.display()),
        }
    }
}

/// The CSV row of `e`, its object named from `objects` (`?` if out of range).
fn pose_row<'a>(e: &'a tracker::track::PoseEstimate, objects: &'a [String]) -> PoseRow<'a> {
    PoseRow {
        t_us: e.t_us,
        object: objects.get(e.object).map_or("?", String::as_str),
        pose: &e.pose,
        quality: e.quality,
        state: e.state.as_str(),
    }
}

impl PoseSink for CsvPoseSink {
    fn name(&self) -> &str {
        &self.name
    }

    fn publish(&mut self, poses: &TickPoses<'_>) -> Result<(), PublishError> {
        if self.objects.len() != poses.objects.len() {
            self.objects = poses.objects.to_vec();
        }
        for e in poses.estimates {
            let r = writeln!(self.out, "{}", pose_row(e, poses.objects));
            match r {
                Ok(()) => self.counters.published += 1,
                Err(err) => {
                    self.counters.failed += 1;
                    return Err(self.io_error(err));
                }
            }
        }
        Ok(())
    }

    fn counters(&self) -> SinkCounters {
        self.counters
    }

    fn flush(&mut self) -> Result<(), PublishError> {
        self.out.flush().map_err(|e| self.io_error(e))?;
        if let Some(out) = &mut self.revised {
            let path = Self::revised_path(&self.path);
            out.flush().map_err(|e| PublishError::Transport {
                sink: self.name.clone(),
                message: format!("cannot write {}: {e}", path.display()),
            })?;
        }
        Ok(())
    }

    /// Appends the revised estimates to `<name>.revised.csv` (a tick may appear there more than once: its last
    /// row is the tracker's final estimate).
    fn revise(&mut self, revised: &[tracker::track::PoseEstimate]) {
        if let Err(e) = self.write_revised(revised) {
            if !self.revision_failed {
                self.revision_failed = true;
                eprintln!(
                    "warning: {}: cannot write {}: {e} (further failures are counted)",
                    self.name,
                    Self::revised_path(&self.path).display()
                );
            }
            self.counters.failed += revised.len() as u64;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivers::timeline::Tick;
    use nalgebra::{Isometry3, Translation3, UnitQuaternion};
    use std::time::Instant;
    use tracker::recording::parse_pose_csv;
    use tracker::track::{PoseEstimate, TrackingState};

    #[test]
    fn rows_read_back_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("poses.csv");
        std::fs::write(dir.path().join("poses.revised.csv"), "from a previous run").unwrap();
        let mut sink = CsvPoseSink::create(&path).unwrap();
        let pose = Isometry3::from_parts(
            Translation3::new(0.1 + 0.2, -1.0 / 3.0, 0.654_321_987_654_321),
            UnitQuaternion::from_euler_angles(0.1, -0.7, 2.9),
        );
        let objects = vec!["mug".to_string(), "can".to_string()];
        let estimates = [
            PoseEstimate {
                object: 1,
                t_us: 8833,
                pose,
                quality: 0.25,
                state: TrackingState::Degraded,
            },
            PoseEstimate {
                object: 0,
                t_us: 8833,
                pose: Isometry3::identity(),
                quality: 1.0,
                state: TrackingState::Tracking,
            },
        ];
        let tick = Tick {
            index: 1,
            t_us: 8833,
            depth_frame: None,
            synthesized: false,
        };
        sink.publish(&TickPoses {
            tick: &tick,
            estimates: &estimates,
            objects: &objects,
            decoded_at: Instant::now(),
        })
        .unwrap();
        sink.flush().unwrap();
        assert_eq!(sink.counters().published, 2);
        let rows = parse_pose_csv(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].object, "can");
        assert_eq!(rows[0].state, "degraded");
        assert_eq!(rows[0].quality, 0.25);
        // Bit-exact translation; the reader renormalises the quaternion (a last-bit change at most).
        assert_eq!(rows[0].pose.translation.vector, pose.translation.vector);
        assert!((rows[0].pose.rotation.coords - pose.rotation.coords).norm() < 1e-15);
        assert_eq!(rows[1].object, "mug");

        // Revisions go beside it, to a file made at the first one; the published rows stay as they were.
        let revised_path = CsvPoseSink::revised_path(&path);
        assert_eq!(revised_path, dir.path().join("poses.revised.csv"));
        assert!(
            !revised_path.exists(),
            "the stale file of a previous run was removed"
        );
        let better = PoseEstimate {
            quality: 0.75,
            state: TrackingState::Tracking,
            ..estimates[0]
        };
        sink.revise(&[better]);
        sink.revise(&[PoseEstimate {
            quality: 0.5,
            ..better
        }]);
        sink.flush().unwrap();
        let revised = parse_pose_csv(&std::fs::read_to_string(&revised_path).unwrap()).unwrap();
        assert_eq!(revised.len(), 2);
        assert_eq!((revised[0].object.as_str(), revised[0].t_us), ("can", 8833));
        assert_eq!((revised[0].quality, revised[1].quality), (0.75, 0.5));
        assert_eq!(
            parse_pose_csv(&std::fs::read_to_string(&path).unwrap()).unwrap(),
            rows
        );
        assert_eq!(sink.counters().failed, 0);
    }

    #[test]
    fn unwritable_path_is_an_error_naming_it() {
        let e = CsvPoseSink::create(Path::new("/nonexistent-dir/x/poses.csv")).unwrap_err();
        assert!(
            e.to_string().contains("/nonexistent-dir/x/poses.csv"),
            "{e}"
        );
    }
}
