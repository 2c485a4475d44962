"""report: analyse one or more rosbag2 bags of mill runs; print a table, write Markdown and plots.

    report runs/slotting-X/bag                          # -> runs/slotting-X/report/report.md
    report adrc/bag pd/bag --out cmp --freqs 60,120     # two runs side by side

Per run and axis, over t >= --skip (the start transient excluded):

- tracking error e = measured position - reference: max |e|, RMS e, and the
  largest RMS of e over any window of --window seconds (a sustained error, where
  max |e| may be one sample);
- contour error: the distance from each measured position to the programmed path (the
  polyline of the reference positions; mill_analysis.metrics.contour_error), max and RMS,
  and a plot of the path against the measured contour with that error magnified;
- disturbance estimation error xi_hat - xi against the plant's ground truth;
- spectrum of e and of xi_hat - xi (Hann window) and their amplitudes at --freqs
  (single-frequency DFT, so a tone between FFT bins is not under-read);
- cutting force and commanded torque statistics; the feed override if the bag
  has /mill/feed_override;
- loop timing: the wall-clock period between consecutive samples as they were
  received (the recorder's publish time; jitter = its standard deviation) and
  the plant's lockstep wait for commands from its /diagnostics status.

max |e|, RMS e, the RMS of xi_hat - xi and of xi and the contour error come from
`mill_analysis.metrics` (summarize, contour_error) on a RunRecord built by
`mill_analysis.lockstep_record.build_record`: the code the runner uses for the summary it
prints, so both agree on the same run.

The bag is read by topic names and types only (see mill_analysis.bag_run), so a
bag from `ros2 bag record` with these topics works too. What kind of run a bag holds (an
axis job in lockstep or in real time, a force job) the bag of `run_scenario --record`
says; another bag's topics and job status tell (kinds).

Modules:

    analysis   bag run -> RunReport: metrics per axis, spectra, windowed RMS, loop timing
               (numpy; no text, no plots)
    text       the table printed on stdout and report.md
    plots      one function per figure; rendered in two forked processes for long runs
    force      the force job's table, report.md and figure
    kinds      one RecordKind per kind of record: how its bags are read, summarised and
               plotted; which kind a bag holds
    cli        `report` (console script) and `python -m mill_analysis.report`: options,
               one-line errors (exit 1, 2 for options), what goes where
"""
