//! `gough mf ...`: the Magic Formula on every row of a CSV file.
use crate::csvio;
use crate::mfrun::{self, InputRow, Precision, INPUT_COLUMNS, OUTPUT_COLUMNS};
use crate::tyre;
use clap::Subcommand;
use gough::mf::Options;
use std::path::PathBuf;

/// `gough mf ...`
#[derive(Subcommand)]
pub enum MfCmd {
    /// Evaluate the steady-state Magic Formula on every row of a CSV file.
    ///
    /// Input columns in_Fz,in_kappa,in_alpha,in_gamma,in_phit,in_Vx,in_P (SI, rad, ISO-W;
    /// in_P = 0 means INFLPRES; other columns are ignored). Output: the input columns, then
    /// Fx,Fy,Mz,Mx,My,mux,muy,Kya,Kxk,t,Mzr,sigmax,sigmay.
    Eval {
        /// Tyre property file (.tir).
        #[arg(long)]
        tir: PathBuf,
        /// Input CSV.
        #[arg(long)]
        input: PathBuf,
        /// Output CSV (written atomically).
        #[arg(long)]
        output: PathBuf,
        /// MFeval useMode: 1xx limits on / 2xx off; x1x alpha* off / x2x on; xx1 no turn slip /
        /// xx2 turn slip.
        #[arg(long, default_value_t = 111)]
        mode: u16,
        /// Float path: f64 (host) or f32 (the device's).
        #[arg(long, value_enum, default_value_t = Precision::F64)]
        precision: Precision,
    },
}

/// Runs a `gough mf` command.
pub fn run(cmd: MfCmd) -> Result<(), String> {
    let MfCmd::Eval {
        tir,
        input,
        output,
        mode,
        precision,
    } = cmd;
    let opts = Options::from_use_mode(mode).ok_or_else(|| {
        format!("--mode {mode}: expected 3 digits, each 1 or 2 (e.g. 111, 211, 121, 221, 112)")
    })?;
    let t = tyre::load(&tir)?;
    let p64 = t.params;
    let p32 = p64.cast::<f32>();
    let table = csvio::read::<InputRow>(&input).map_err(|e| e.to_string())?;
    let mut rows = Vec::with_capacity(table.rows.len());
    for (row, line) in table.rows.iter().zip(&table.lines) {
        let out = mfrun::eval_row(&p64, &p32, &row.input(), &opts, precision)
            .map_err(|e| format!("{}: line {line}: {e}", input.display()))?;
        let mut r = row.values().to_vec();
        r.extend_from_slice(&mfrun::output_values(&out));
        rows.push(r);
    }
    let header: Vec<&str> = INPUT_COLUMNS
        .iter()
        .chain(OUTPUT_COLUMNS.iter())
        .copied()
        .collect();
    csvio::write(&output, &header, &rows)
        .map_err(|e| format!("{}: cannot write: {e}", output.display()))?;
    eprintln!("{} rows -> {}", rows.len(), output.display());
    Ok(())
}
