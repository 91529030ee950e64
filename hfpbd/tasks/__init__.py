"""The paper's five programming tasks, end to end: scripts as data, a live runner, the benchmark."""
