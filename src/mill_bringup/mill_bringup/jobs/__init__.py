"""Kinds of job (jobs.base: the interface; jobs.registry: which kind a scenario runs)."""
