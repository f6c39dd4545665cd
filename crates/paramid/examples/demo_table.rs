//! The figures of docs/paramid.md's ground-programme table: `helicon ident
//! demo` on each shipped truth at several seeds (ground experiments, the
//! three default flights, no verification flight), one line per run: each
//! parameter's error against the truth with its Cramér–Rao bound and the
//! ratio, the flagged ones, the ground values' errors, the cost and the
//! cost against the truth's model responses.
//!
//! `cargo run --release -p helicon-paramid --example demo_table -- [--no-ground] [--fix-ground] [--fix=KEY]... [TRUTH SEED]...`
//! (default: truth-a, truth-b, truth-c at seeds 1, 3 and 7).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::print_stdout)]

use helicon_model::Params;
use helicon_paramid::demo::{DemoOptions, TRUTHS, run_demo};
use helicon_paramid::keys;

fn short(key: &str) -> String {
    match key {
        "main_rotor.lift_slope_per_rad" => "Cla".into(),
        "main_rotor.drag_coefficient" => "Cd".into(),
        "main_rotor.blade_inertia_kg_m2" => "Ib".into(),
        "main_rotor.spring_n_m_per_rad" => "Ks".into(),
        "stabilizer_bar.lift_slope_per_rad" => "Cla_sb".into(),
        "tail_rotor.lift_slope_per_rad" => "Cla_tr".into(),
        k => k.replace("servo.", "").replace(".omega_n_rad_s", "_wn"),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let ground = !args.iter().any(|a| a == "--no-ground");
    // --fix-ground: the flight does not identify the ground-measured lift
    // slopes and drag coefficient again (the hinge spring stays free)
    let fix_ground = args.iter().any(|a| a == "--fix-ground");
    let parameters: Vec<String> = helicon_paramid::demo::DEMO_PARAMETERS
        .iter()
        .filter(|k| {
            !fix_ground
                || !matches!(
                    **k,
                    "main_rotor.lift_slope_per_rad"
                        | "main_rotor.drag_coefficient"
                        | "tail_rotor.lift_slope_per_rad"
                )
        })
        // --fix=KEY (repeatable): KEY is not identified in flight (kept at
        // its start value, the ground-measured one for a ground key)
        .filter(|k| !args.iter().any(|a| a.strip_prefix("--fix=") == Some(**k)))
        .map(|k| k.to_string())
        .collect();
    let rest: Vec<&String> = args.iter().filter(|a| !a.starts_with("--")).collect();
    let mut runs: Vec<(String, u64)> = rest
        .chunks(2)
        .map(|c| (c[0].clone(), c[1].parse().unwrap()))
        .collect();
    if runs.is_empty() {
        for t in ["truth-a", "truth-b", "truth-c"] {
            for s in [1, 3, 7] {
                runs.push((t.into(), s));
            }
        }
    }
    for (name, seed) in runs {
        let text = TRUTHS.iter().find(|t| t.0 == name).unwrap().1;
        let t = Params::from_toml_str(text, &name).unwrap();
        let dir = std::env::temp_dir().join(format!("helicon-demo-table-{name}-{seed}"));
        let opts = DemoOptions {
            seed: Some(seed),
            verify: false,
            ground,
            parameters: parameters.clone(),
            ..DemoOptions::default()
        };
        let mut id = run_demo(&t, &dir, &opts).unwrap();
        if args.iter().any(|a| a == "--on-axis") {
            // refit on the on-axis responses alone (p/S_lat, q/S_lon)
            let mut data = id.data.clone();
            for d in &mut data {
                d.responses.retain(|m| {
                    matches!(
                        (m.response.input.as_str(), m.response.output.as_str()),
                        ("S_lat", "meas_p") | ("S_lon", "meas_q")
                    )
                });
            }
            let (g, _) = (id.ground.clone(), ());
            id = helicon_paramid::report::run_on(&id.config, data).unwrap();
            id.ground = g;
            id.truth_model_cost = Some(id.truth_model_cost(&t, None).unwrap());
        }
        let r = id.report();
        let mut line = format!("{name} s{seed}:");
        let mut worst: f64 = 0.0;
        for p in &r.parameters {
            let want = keys::get(&t, keys::find(&p.key).unwrap());
            let err = 100.0 * (p.identified - want) / want;
            if p.identifiable {
                let cr = p.cramer_rao_pct.unwrap();
                worst = worst.max(err.abs() / cr);
                line += &format!(
                    " {} {err:+.1}({cr:.1};{:.2})",
                    short(&p.key),
                    err.abs() / cr
                );
            } else {
                let why = p
                    .reason
                    .as_deref()
                    .unwrap_or("")
                    .split(':')
                    .next()
                    .unwrap_or("");
                line += &format!(" {} flagged[{why}] {err:+.1}", short(&p.key));
            }
        }
        println!("{line}");
        let mut g = String::from("   ground:");
        for v in &r.ground {
            let want = keys::get(&t, keys::find(&v.key).unwrap());
            g += &format!(
                " {} {:+.2}%({:.2}%)",
                short(&v.key),
                100.0 * (v.value - want) / want,
                100.0 * v.std_error / v.value
            );
        }
        let tm = r.truth_model_cost.unwrap();
        let mut per = String::from("   identified cost per response:");
        for c in &r.costs {
            per += &format!(" {}:{} {:.0}", c.operating_point, c.response, c.identified);
        }
        println!("{per}");
        println!(
            "{g}\n   worst {worst:.2} bounds; cost {:.0} -> {:.0}; truth-model {}{:.3e} -> {:.3e} ({:.0}x)",
            r.cost_start,
            r.cost_identified,
            tm.before_ground
                .map_or(String::new(), |b| format!("before ground {b:.3e}, ")),
            tm.start,
            tm.identified,
            tm.start / tm.identified
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
