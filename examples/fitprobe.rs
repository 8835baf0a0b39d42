//! Probe: fit the ASTM sizes and print residuals.
use grade3d::mannequin::fit::{fit_size, FitOptions};
use grade3d::mannequin::model::BodyModel;
use grade3d::mannequin::size_chart::{parse_csv, SizeChartOptions};

fn main() {
    let model = BodyModel::embedded().unwrap();
    let chart = parse_csv(
        include_str!("../fixtures/size-charts/astm-d5585-11-misses-partial.csv"),
        &SizeChartOptions::default(),
    )
    .unwrap();
    let which: Vec<String> = std::env::args().skip(1).collect();
    for row in &chart.rows {
        if !which.is_empty() && !which.contains(&row.size) {
            continue;
        }
        let t = std::time::Instant::now();
        match fit_size(model, row, &FitOptions::default()) {
            Ok(f) => {
                print!("size {:>3} {:?} it {} rounds {} ", f.size, t.elapsed(), f.iterations, f.scaling_rounds);
                for (k, r) in &f.residuals {
                    print!("{}={:+.2} ", k, r.error_mm());
                }
                println!();
                println!(
                    "   params w={:.2} {:?} scales {:?}",
                    f.params.macros.weight, f.params.modifiers, f.profile_scales
                );
            }
            Err(e) => println!("size {} ERR {e}", row.size),
        }
    }
}
