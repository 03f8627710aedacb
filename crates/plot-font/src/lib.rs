//! The font for plot text, and the error both plotting crates report.
//! plotters' ab_glyph backend draws text from a TTF
//! registered at run time (no fontconfig, nothing to install but the font),
//! and both the optimiser's report plots (gait-opt) and the closed-loop
//! plots (sim) need the same one, found the same way: `$EXOGAIT_FONT`, else
//! DejaVu Sans or Liberation Sans from the usual Debian paths.

use std::sync::OnceLock;

use plotters::style::FontStyle;

/// Where a font is looked for after `$EXOGAIT_FONT`, in order.
pub const FONT_PATHS: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
];

/// Registers the first readable font as plotters' "sans-serif" (once per
/// process; later calls return the first call's outcome). The error says
/// where it looked.
pub fn ensure_font() -> Result<(), String> {
    static FONT: OnceLock<Result<(), String>> = OnceLock::new();
    FONT.get_or_init(|| {
        let mut paths: Vec<String> = std::env::var("EXOGAIT_FONT").into_iter().collect();
        paths.extend(FONT_PATHS.iter().map(|s| s.to_string()));
        for p in &paths {
            if let Ok(bytes) = std::fs::read(p) {
                // plotters keeps the font for the life of the process.
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                if plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok() {
                    return Ok(());
                }
            }
        }
        Err(format!("tried $EXOGAIT_FONT and {}", FONT_PATHS.join(", ")))
    })
    .clone()
}

/// Why a plot could not be drawn (gait-opt's report plots and sim's
/// closed-loop plots alike).
#[derive(Debug)]
pub enum PlotError {
    /// No usable TTF font was found (the message lists where we looked).
    NoFont(String),
    /// The drawing backend failed.
    Draw(String),
}

impl std::fmt::Display for PlotError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NoFont(m) => write!(f, "no font for plot text: {m}"),
            Self::Draw(m) => write!(f, "plot: {m}"),
        }
    }
}

impl std::error::Error for PlotError {}

/// [`ensure_font`] as a [`PlotError`].
pub fn font_ready() -> Result<(), PlotError> {
    ensure_font().map_err(PlotError::NoFont)
}

/// Any backend error as a [`PlotError`].
pub fn draw_err<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError::Draw(e.to_string())
}
