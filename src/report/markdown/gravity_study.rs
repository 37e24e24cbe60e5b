//! Gravity error against the poses measured (when the run made the study): the worst joint's
//! error per design, size and input encoding.

use std::fmt::Write as _;

use super::row;
use crate::experiments::paper::PaperRun;
use crate::experiments::GravityDesign;

/// Appends the section "Gravity error against the poses measured" if the run made the study.
pub(super) fn write(s: &mut String, run: &PaperRun) {
    let g = &run.results.gravity;
    if let Some(study) = &g.study {
        let _ = writeln!(s, "\n## Gravity error against the poses measured\n");
        let _ = writeln!(
            s,
            "The paper concludes that gravity data grow as x^(a·DOF). Here every kⁿ grid up to {} poses is swept on its own, and \
             the sampled designs are the first N poses drawn of one sweep of {} sampled poses; on each, one net per input \
             encoding ({} hidden neurons, the run's training), tested over the whole turn on {} random poses. Worst joint's RMS \
             and largest error, as shares of that joint's own largest gravity torque (`gravity_study.png`; every joint in \
             `results.json` and `data/gravity_study.csv`, where grid_per_joint 0 marks a sampled design and encoding is 0 raw, 1 \
             joint angles, 2 link angles). Measuring took {:.1} s, training {:.1} s.\n",
            study.largest, study.largest, g.hidden, g.net.poses, study.measure_s, study.train_s
        );
        let _ = writeln!(
            s,
            "| design | poses | link angles: RMS | largest | joint angles: RMS | largest | raw (paper): RMS | largest |\n| --- | --- | --- | --- | --- | --- | --- | --- |"
        );
        for chunk in study.points.chunks(3) {
            let design = match chunk[0].design {
                GravityDesign::Grid { per_joint } => format!("{per_joint}ⁿ grid"),
                GravityDesign::Sampled { .. } => "sampled".into(),
            };
            let mut cells = vec![design, chunk[0].poses.to_string()];
            for p in chunk {
                cells.push(format!("{:.3} %", 100.0 * p.worst_rms_share()));
                cells.push(format!("{:.3} %", 100.0 * p.worst_max_share()));
            }
            let _ = writeln!(s, "{}", row(&cells));
        }
        let _ = writeln!(s);
    }
}
