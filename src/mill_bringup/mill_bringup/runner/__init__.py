"""run_scenario: a scenario's job across processes, followed to its end, its record collected.

    run_scenario slotting                      # the Beltrán 2013 job, 8 processes
    run_scenario slotting --controller pd      # the uncompensated run
    run_scenario slotting --duration 5 --compare-offline
    run_scenario slotting --record             # also write the run to a rosbag2 bag (RUN_DIR/bag)
    run_scenario rubio --variant scheme1       # one configuration of a scenario with variants
    run_scenario slotting --namespace machine2 # every topic under /machine2 (and the monitor)

The same steps for every kind of job (mill_bringup.jobs), one module each:

    options  RunOptions: how a job runs (what run_scenario's options set); RunError
    start    plan: which processes start first, which clock nodes wait to be activated;
             start: the nodes, then, once the monitor hears them, the node that clocks the job
    session  Session: the runner's side of the graph (its monitor node, the node processes,
             the progress display), stopped and shut down however the run ends
    follow   follow the job with a progress bar until it is complete; a node that exits or
             nothing happening for --stall-timeout ends the run
    collect  stop the graph, close the bag, build the record from the monitor's messages;
             the RunResult (the job's summary, wall time, real-time factor, memory)
    result   RunResult and its text; the exit code (0 good and complete, 1 the job failed,
             3 a good job whose record is incomplete)
    run      run(job, run_dir, options): plan, start, follow, collect; however the run ends
             once its graph started (a drive gone silent, a node that died), a RunResult
    cli      the run_scenario command: checks every variant's scenario before anything
             starts, runs each, prints its summary and the paper's verdicts; logs and
             summary.json go to the run directory (--output)

With --record the monitor also writes every topic of the graph to a rosbag2 bag in MCAP
storage; `report BAG` (mill_analysis) analyses it.
"""
