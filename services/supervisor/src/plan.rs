//! What a run will do, decided and checked before anything starts: the
//! configuration (defaults < `--config` file < the scenario's `[config]` <
//! `--set`), typed and range-checked by phri-config, checked against the
//! robot model; the services in start order; the run length; what the
//! evaluator needs (the detector, the model's link names).

use std::path::Path;

use phri_config::{Loaded, ServiceSpec};
use phri_ipc::Reaction;

use crate::error::SupervisorError;
use crate::report::{DetectorInfo, Evaluator, StaleBounds};
use crate::spec::in_start_order;

/// A run, validated.
#[derive(Clone, Debug)]
pub struct Plan {
    /// the merged configuration, its scenario, and the table the services get
    pub loaded: Loaded,
    /// enabled services in start order
    pub services: Vec<(String, ServiceSpec)>,
    /// run length \[s\]; `None`: until SIGINT/SIGTERM
    pub duration_s: Option<f64>,
    /// the residual detector, resolved for the robot's joints
    pub detector: DetectorInfo,
    /// the robot model's collision objects by index (contact reports)
    pub link_names: Vec<String>,
    /// the robot model's name (its URDF's)
    pub model_name: String,
}

impl Plan {
    /// Load `config` (a file over the built-in defaults), `scenario` (a file
    /// or a name in `scenarios/` beside `config`) and `sets`
    /// (`section.key=value`); check everything, the robot model included.
    /// The run lasts `duration_s` if given, else the scenario's `duration_s`
    /// when a scenario is given, else until stopped.
    pub fn load(
        config: &Path,
        scenario: Option<&str>,
        sets: &[&str],
        duration_s: Option<f64>,
    ) -> Result<Plan, SupervisorError> {
        if duration_s.is_some_and(|d| {
            !(d.is_finite() && d > 0.0 && d <= phri_config::scenario::MAX_DURATION_S)
        }) {
            return Err(SupervisorError::Duration);
        }
        let loaded = Loaded::load(config, scenario, sets)?;
        Self::from_loaded(loaded, scenario.is_some(), duration_s)
    }

    /// As [`Plan::load`], from a configuration already loaded (`scenario_given`:
    /// whether it was loaded with a scenario, whose length then bounds the run).
    pub fn from_loaded(
        loaded: Loaded,
        scenario_given: bool,
        duration_s: Option<f64>,
    ) -> Result<Plan, SupervisorError> {
        let model = loaded.model()?;
        let detector = DetectorInfo::from_config(&loaded.config.dynamics, model.nv())?;
        let link_names = model.collisions.iter().map(|c| c.link.clone()).collect();
        let services = in_start_order(&loaded.config.services);
        let duration_s = duration_s.or(scenario_given.then_some(loaded.scenario.duration_s));
        Ok(Plan {
            loaded,
            services,
            duration_s,
            detector,
            link_names,
            model_name: model.name.clone(),
        })
    }

    /// The arm the cell drives (the report's `robot`); its `kind` is the
    /// service that serves `robot/state` (`sim` or `franka`).
    pub fn robot_report(&self) -> crate::report::RobotReport {
        crate::report::RobotReport {
            kind: match self.loaded.config.robot.ip.is_empty() {
                true => "sim",
                false => "franka",
            }
            .into(),
            name: self.loaded.config.robot.name.clone(),
            model: self.model_name.clone(),
            ..Default::default()
        }
    }

    /// The scenario's name (the report's `scenario`).
    pub fn scenario_name(&self) -> &str {
        &self.loaded.scenario.name
    }

    /// The report's `degraded` lines for the safety functions the
    /// configuration switches off on purpose (`control.avoidance = false`,
    /// `ssm.enabled = false`, a perception or residual service dropped), each
    /// naming the key and the file or `--set` that switched it off.
    pub fn safety_off(&self) -> Vec<String> {
        self.loaded
            .safety_off()
            .iter()
            .map(|o| o.to_string())
            .collect()
    }

    /// The configured reaction to a detected collision (named in the report's events).
    pub fn reaction(&self) -> Reaction {
        self.loaded.config.control.reaction
    }

    /// The merged configuration the services read (`<run-dir>/config.toml`).
    pub fn merged_toml(&self) -> String {
        self.loaded.to_toml()
    }

    /// An evaluator of this run, started at `t0_ns`.
    /// The `collaboration` section's evaluation, with the scenario's wave onsets.
    pub fn collab_evaluator(&self, t0_ns: u64) -> crate::collab_report::CollabEvaluator {
        let waves = self
            .loaded
            .scenario
            .human
            .as_ref()
            .map(|h| {
                h.keyframes()
                    .iter()
                    .filter(|k| k.wave.is_some())
                    .map(|k| k.t)
                    .collect()
            })
            .unwrap_or_default();
        let period_ns = (self.loaded.config.sim.dt_s * 1e9).round() as u64;
        crate::collab_report::CollabEvaluator::new(t0_ns, waves, period_ns)
    }

    /// The microphone's source and device as the report names them.
    fn mic_names(&self) -> (&'static str, &str) {
        let mic = &self.loaded.config.mic;
        match mic.source {
            phri_config::MicSource::Sim => ("sim", "sim"),
            phri_config::MicSource::Alsa => ("alsa", mic.device.as_str()),
        }
    }

    /// The report's evaluation of this run, its time origin `t0_ns` \[ns,
    /// CLOCK_MONOTONIC\]: staleness bounds, robot, period and sensors as planned.
    pub fn evaluator(&self, t0_ns: u64) -> Evaluator {
        // the controller's perception comes from the repulsion workers
        let perception = self
            .services
            .iter()
            .any(|(_, s)| s.binary == "phri-repulsion");
        Evaluator::new(t0_ns, self.detector.clone(), self.link_names.clone())
            .with_stale_bounds(StaleBounds::from_config(
                &self.loaded.config.control,
                perception,
            ))
            .with_robot_service(&self.robot_report().kind)
            .with_period(self.loaded.config.sim.dt_s)
            .with_sensors(
                self.loaded
                    .config
                    .cameras
                    .iter()
                    .map(|c| c.source.name().to_string())
                    .collect(),
                (0..self.loaded.config.cameras.len())
                    .map(|i| self.loaded.config.skeleton_source(i).name().to_string())
                    .collect(),
                self.mic_names(),
            )
    }

    /// Every service's binary is an executable file in `bin_dir`.
    pub fn check_binaries(&self, bin_dir: &Path) -> Result<(), SupervisorError> {
        for (name, spec) in &self.services {
            let path = bin_dir.join(&spec.binary);
            match crate::process::check_executable(&path) {
                Ok(()) => {}
                Err(crate::process::BinaryError::Missing) => {
                    return Err(SupervisorError::MissingBinary {
                        service: name.clone(),
                        binary: spec.binary.clone(),
                        dir: bin_dir.to_path_buf(),
                    })
                }
                Err(e) => {
                    return Err(SupervisorError::BadBinary {
                        service: name.clone(),
                        path,
                        reason: e.to_string(),
                    })
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn deploy() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../deploy/phri.toml")
    }

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!(
            "phri-supervisor-plan-{}-{name}",
            std::process::id()
        ));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_scenario_names_the_run_sets_its_length_and_its_overrides_reach_the_services() {
        let p = Plan::load(
            &deploy(),
            Some("collision"),
            &["control.reaction=\"admittance\""],
            None,
        )
        .unwrap();
        assert_eq!(p.scenario_name(), "collision");
        assert_eq!(p.duration_s, Some(16.0));
        assert_eq!(p.reaction(), Reaction::Admittance);
        assert_eq!(
            p.detector.collision_threshold,
            [8.0, 8.0, 6.0, 6.0, 4.0, 3.0, 2.0]
        );
        assert_eq!(p.detector.gain, 100.0);
        assert!(!p.link_names.is_empty());
        assert_eq!(p.services[0].0, "sim");
        // the services read one self-contained file: the scenario and the robot by absolute path
        let merged: toml::Table = p.merged_toml().parse().unwrap();
        let file = merged["scenario"]["file"].as_str().unwrap();
        assert!(
            Path::new(file).is_absolute() && file.ends_with("collision.toml"),
            "{file}"
        );
        assert_eq!(merged["scenario"]["name"].as_str(), Some("collision"));
        assert!(Path::new(merged["robot"]["urdf"].as_str().unwrap()).is_absolute());
        assert_eq!(merged["control"]["reaction"].as_str(), Some("admittance"));
        // --duration wins over the scenario's; without a scenario the run has no end
        let p = Plan::load(&deploy(), Some("collision"), &[], Some(3.0)).unwrap();
        assert_eq!(p.duration_s, Some(3.0));
        let p = Plan::load(&deploy(), None, &[], None).unwrap();
        assert_eq!((p.duration_s, p.scenario_name()), (None, "free-motion"));
    }

    #[test]
    fn refusals_name_the_flag_file_or_key() {
        let err = |r: Result<Plan, SupervisorError>| r.unwrap_err().to_string();
        assert_eq!(
            err(Plan::load(&deploy(), None, &[], Some(0.0))),
            "--duration: must be a positive number of seconds, at most 1e7 (116 days)"
        );
        // 2^64 ns and more would overflow the clock: refused, never "over at once"
        for d in [f64::NAN, f64::INFINITY, -5.0, 2e10] {
            assert_eq!(
                err(Plan::load(&deploy(), None, &[], Some(d))),
                "--duration: must be a positive number of seconds, at most 1e7 (116 days)",
                "{d}"
            );
        }
        let e = err(Plan::load(&deploy(), Some("no-such-scenario"), &[], None));
        assert!(
            e.contains("--scenario") && e.contains("no-such-scenario"),
            "{e}"
        );
        let e = err(Plan::load(
            Path::new("/nonexistent/phri.toml"),
            None,
            &[],
            None,
        ));
        assert!(e.contains("/nonexistent/phri.toml"), "{e}");
        let e = err(Plan::load(
            &deploy(),
            None,
            &["supervisor.health_hz=-1"],
            None,
        ));
        assert!(e.contains("supervisor.health_hz"), "{e}");
        // per-joint lists are checked against the model before anything starts
        let e = err(Plan::load(
            &deploy(),
            None,
            &["dynamics.collision_threshold=[1.0, 2.0]"],
            None,
        ));
        assert!(e.contains("dynamics.collision_threshold"), "{e}");
        let e = err(Plan::load(
            &deploy(),
            None,
            &["robot.urdf=\"/nonexistent/robot.urdf\""],
            None,
        ));
        assert!(e.contains("/nonexistent/robot.urdf"), "{e}");
        assert_eq!(e.lines().count(), 1, "{e}");
        // a camera past the channels
        let e = err(Plan::load(
            &deploy(),
            None,
            &["camera=[{},{},{},{},{}]"],
            None,
        ));
        assert!(e.contains("camera") && e.contains("at most 4"), "{e}");
        assert_eq!(e.lines().count(), 1, "{e}");
    }

    #[test]
    fn a_safety_function_switched_off_is_a_degraded_line_naming_what_did_it() {
        let p = Plan::load(&deploy(), None, &[], None).unwrap();
        assert!(p.safety_off().is_empty());
        let p = Plan::load(
            &deploy(),
            Some("free-motion"),
            &["control.avoidance=false", "ssm.enabled=false"],
            None,
        )
        .unwrap();
        assert_eq!(
            p.safety_off(),
            [
                "collision avoidance switched off (control.avoidance by --set control.avoidance=false)",
                "speed and separation monitoring switched off (ssm.enabled by --set ssm.enabled=false)"
            ]
        );
    }

    #[test]
    fn two_cameras_start_a_camera_and_an_ingestion_each_and_share_the_workers() {
        let p = Plan::load(
            &deploy().with_file_name("two-cameras.toml"),
            None,
            &[],
            None,
        )
        .unwrap();
        let names: Vec<&str> = p.services.iter().map(|(n, _)| n.as_str()).collect();
        for n in [
            "camera",
            "camera-1",
            "perception",
            "perception-1",
            "repulsion0",
        ] {
            assert!(names.contains(&n), "{names:?}");
        }
        // the second camera's ingestion starts after its camera
        let at = |n: &str| names.iter().position(|x| *x == n).unwrap();
        assert!(at("camera-1") < at("perception-1"));
        assert!(p.services.len() <= phri_config::MAX_ROSTER);
    }

    #[test]
    fn disabled_services_are_not_started_and_binaries_must_exist() {
        let p = Plan::load(&deploy(), None, &["services.camera.enabled=false"], None).unwrap();
        assert!(p.services.iter().all(|(n, _)| n != "camera"));
        let dir = tmp("bins");
        let e = p.check_binaries(&dir).unwrap_err().to_string();
        assert!(
            e.starts_with("[services.sim] binary 'phri-sim' not found in"),
            "{e}"
        );
        use std::os::unix::fs::PermissionsExt;
        for (_, spec) in &p.services {
            let f = dir.join(&spec.binary);
            std::fs::write(&f, "").unwrap();
            std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o755)).unwrap();
        }
        p.check_binaries(&dir).unwrap();
        // a file that exists but cannot be executed is refused before anything starts
        let control = dir.join("phri-control");
        std::fs::set_permissions(&control, std::fs::Permissions::from_mode(0o644)).unwrap();
        let e = p.check_binaries(&dir).unwrap_err().to_string();
        assert!(
            e.starts_with("[services.control] binary") && e.contains("not executable"),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
