"""The contract module against its readers: the NLU derives from it, the executor publishes what the NLU reads."""

from __future__ import annotations

from services.executor.reach import REACH_KEYS as PUBLISHED
from services.nlu.commands import PROCEDURES as ENUMERATED
from services.nlu.infer import Model
from services.nlu.prior import READ_KEYS
from services.nlu.templates import sentence_templates
from services.nlu.world import parse_world
from shared import contract
from tests.nlu.scenes import table_scene


def test_every_reach_key_the_nlu_reads_is_one_the_executor_publishes() -> None:
    assert READ_KEYS <= set(PUBLISHED)
    assert set(contract.REACH_KEYS) == set(PUBLISHED)


def test_the_nlu_enumerates_exactly_the_contract_procedures_and_required_arguments() -> None:
    enumerable = [name for name in contract.PROCEDURES if name not in contract.SKILL_PROCEDURES]
    assert list(ENUMERATED) == enumerable
    for name in enumerable:
        assert list(ENUMERATED[name]) == [p.name for p in contract.PROCEDURES[name].required]
    assert len(contract.PAPER_PROCEDURES) == 17


def test_both_arms_only_where_the_contract_allows_them() -> None:
    with_both = {name for name, p in contract.PROCEDURES.items() if contract.BOTH in p.arms}
    assert with_both == {"open", "close", "move_abs_dir", "move_abs_dest"}


def test_distance_limits_hold_together() -> None:
    limits = contract.DISTANCE
    assert limits.min_m < limits.a_little_m < limits.default_m < limits.a_lot_m < limits.max_m
    assert limits.allows(0.05) and not limits.allows(0.5) and not limits.allows(0.005)


def test_the_default_words_are_the_ones_the_nlu_says() -> None:
    model = Model(parse_world(table_scene()))
    for name, procedure in contract.PROCEDURES.items():
        if name in contract.SKILL_PROCEDURES:
            continue  # built by their own reader, from what was said
        command = next(c for c in model.index.commands if c.procedure == name)
        assert model.describe_command(command).startswith(procedure.verb)


def test_every_procedure_has_sentence_shapes_for_the_speech_grammar() -> None:
    templates = sentence_templates()
    assert set(templates["procedures"]) == set(ENUMERATED)  # type: ignore[arg-type]
    assert all(templates["verbs"][name] for name in ENUMERATED)  # type: ignore[index]
