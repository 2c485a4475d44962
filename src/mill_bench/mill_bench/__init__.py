"""How fast mill runs on this machine, and what bounds it.

    benchmark       the lockstep job in each process layout (steps/s, CPU, memory), the cost
                    of recording, the algorithm cores alone; with the figures below
    realtime_sweep  the sample rates each layout holds on the wall clock
    floor           the job's graph with empty callbacks: what transport and executor allow
    pingpong        an rclpy round trip between two processes: the transport's own limit

Nothing here is needed to run a job; no other package imports this one.
"""
