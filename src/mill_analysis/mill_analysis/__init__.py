"""What a mill run gives: its record, its metrics, the papers' verdicts and the bag report.

Everything here reads messages (serialized, as the runner's monitor keeps them) or bags;
nothing starts or simulates a graph, so this package imports neither mill_bringup nor
any role package.

    metrics          RunRecord (the three-axis job's signals) and summarize
    lockstep_record  messages -> RunRecord on the sample grid (build_record)
    bag_run          a bag -> its record and status (read_run)
    node_intake      the nodes' checks on a listener's messages in arrival order (Intake)
    realtime_record  the same on the drive's own stamps (a realtime run), command timing
    bag_status       what a run's /diagnostics say: job start and end, the plant's status
    force_record     ForceRecord of a cutting-force job (Rubio 2013), J_c of eq. (14)
    force_windows    mean force and override of a recorded run per time window
    papers           each paper's metrics and verdicts from the records of its variants
    records          the kinds of record by name, as a bag of run_scenario --record says;
                     its notes (missing samples, owners); the lines of missing samples
    report/          `report BAG ...`
"""
