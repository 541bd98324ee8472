//! Frame times over the last second, for the inspector and for measured
//! sessions: with `LODSTUDIO_FRAME_STATS` set, one line per second on stderr
//! (frames, median and largest interval, median CPU time, whether a build ran).
//! Fixed-size buffers: nothing is allocated per frame.

/// Frames kept per window (a second at up to 256 fps).
const CAPACITY: usize = 256;

#[derive(Debug, Clone)]
pub struct FrameStats {
    intervals: [f32; CAPACITY],
    cpu: [f32; CAPACITY],
    len: usize,
    building: bool,
    window_start: Option<f64>,
    report: bool,
    /// The last full window's median interval and CPU time (ms).
    pub median_ms: f32,
    pub median_cpu_ms: Option<f32>,
}

impl Default for FrameStats {
    fn default() -> Self {
        Self {
            intervals: [0.0; CAPACITY],
            cpu: [0.0; CAPACITY],
            len: 0,
            building: false,
            window_start: None,
            report: std::env::var_os("LODSTUDIO_FRAME_STATS").is_some(),
            median_ms: 0.0,
            median_cpu_ms: None,
        }
    }
}

impl FrameStats {
    /// One frame at time `now` (seconds): its interval since the last frame,
    /// its CPU time where known, and whether a build was running.
    /// Whether the statistics (and the log) go to stderr.
    pub fn reporting(&self) -> bool {
        self.report
    }

    pub fn record(&mut self, now: f64, interval_ms: f32, cpu_ms: Option<f32>, building: bool) {
        let start = *self.window_start.get_or_insert(now);
        if self.len < CAPACITY {
            self.intervals[self.len] = interval_ms;
            self.cpu[self.len] = cpu_ms.unwrap_or(f32::NAN);
            self.len += 1;
        }
        self.building |= building;
        if now - start < 1.0 {
            return;
        }
        let n = self.len;
        let intervals = &mut self.intervals[..n];
        intervals.sort_unstable_by(f32::total_cmp);
        self.median_ms = intervals[n / 2];
        let largest = intervals[n - 1];
        let cpu = &mut self.cpu[..n];
        cpu.sort_unstable_by(f32::total_cmp);
        // NaNs (no CPU time) sort last.
        let known = cpu.iter().take_while(|c| !c.is_nan()).count();
        self.median_cpu_ms = (known > 0).then(|| cpu[known / 2]);
        if self.report {
            eprintln!(
                "frames {n} interval median {:.1} ms max {largest:.1} ms cpu median {} building {}",
                self.median_ms,
                self.median_cpu_ms
                    .map_or("-".to_string(), |c| format!("{c:.1} ms")),
                self.building
            );
        }
        self.len = 0;
        self.building = false;
        self.window_start = Some(now);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_window_closes_after_a_second_with_its_medians() {
        let mut s = FrameStats::default();
        for i in 0..=20 {
            let interval = if i % 2 == 0 { 40.0 } else { 60.0 };
            s.record(i as f64 * 0.05, interval, Some(i as f32), false);
        }
        // 11 intervals of 40 ms and 10 of 60 ms.
        assert_eq!(s.median_ms, 40.0);
        assert_eq!(s.median_cpu_ms, Some(10.0));
        // A new window started: the next frame alone does not close it.
        s.record(1.05, 500.0, None, true);
        assert_eq!(s.median_ms, 40.0);
    }
}
