"""The ``hfpbd`` command and what stands above the services: the launcher, the benchmarks and the task runner.

Why a package of its own: ``shared/`` is the bottom layer every service stands
on and must import no service; what starts, drives or measures the services
lives here instead.
"""
