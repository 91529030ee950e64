"""The ``pbd/<ns>/...`` key scheme (fixed by the design notes) in one place."""

from __future__ import annotations

from dataclasses import dataclass

SERVICES = ("sim", "perception", "nlu", "executor", "tui", "speech")


@dataclass(frozen=True)
class Keys:
    """Key expressions of one robot's namespace."""

    namespace: str = "default"

    def _key(self, suffix: str) -> str:
        return f"pbd/{self.namespace}/{suffix}"

    @property
    def cloud(self) -> str:
        return self._key("sim/cloud")

    @property
    def sim_state(self) -> str:
        return self._key("sim/state")

    @property
    def truth(self) -> str:
        return self._key("sim/truth")

    def sim_control(self, name: str) -> str:
        return self._key(f"sim/control/{name}")

    @property
    def sim_events(self) -> str:
        return self._key("sim/events")

    @property
    def objects(self) -> str:
        return self._key("perception/objects")

    @property
    def record(self) -> str:
        return self._key("perception/record")

    @property
    def utterance(self) -> str:
        return self._key("dialog/utterance")

    @property
    def say(self) -> str:
        return self._key("dialog/say")

    @property
    def nlu_result(self) -> str:
        return self._key("nlu/result")

    def nlu_query(self, verb: str) -> str:
        return self._key(f"nlu/{verb}")

    @property
    def executor_state(self) -> str:
        return self._key("executor/state")

    def executor_control(self, name: str) -> str:
        return self._key(f"executor/control/{name}")

    def speech(self, name: str) -> str:
        """``speech/audio`` (PCM in), ``speech/ptt`` (push-to-talk), ``speech/status``."""
        return self._key(f"speech/{name}")

    def alive(self, service: str) -> str:
        return self._key(f"alive/{service}")

    @property
    def alive_all(self) -> str:
        return self._key("alive/*")

    def service_of(self, alive_key: str) -> str:
        """The service name at the end of an ``alive/<service>`` key."""
        return str(alive_key).rsplit("/", 1)[-1]
