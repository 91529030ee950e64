"""Every tunable number of the language model, in one place.

Why one place: the paper stresses that only the *relative* magnitudes of these
numbers matter, so they are kept side by side where their order can be read
and tested at a glance.

Prior P(C|S) (log scale, added to a command's score; 0 = no opinion):

    holding move (-0.2)  <  unused arm + novel object  (-1.0)  <  unreachable (-2.5)  <  impossible (-6.0)

- ``holding_move``: a relative destination move with a hand that holds
  something; with no verb said, "on the blue cup" then means placing there
  (the paper's gripper-state rule between move, pick up and place). Smaller
  than any other penalty, so it only breaks ties.
- ``novel_object``: the command refers to an object other than the last referred one.
- ``unused_arm``: the command uses the arm that was not used last.
- ``unreachable``: the reachability map says that arm cannot do that with that
  object, or a directional move would leave the arm's reachable space.
- ``far_side``: no hand has been used yet and the object lies on the other
  arm's side of the robot (beyond ``Margins.side_m``); the nearer arm is taken.
  ``middle_side``: the same for an object in the middle, by the sign of its y
  (right at 0), just above the ``Decision.tie`` so a first "pick up the box"
  is done rather than answered with "Which hand?".
- ``beyond_both``: neither hand reaches the object to pick it up (the executor
  will lower the torso for it) and it lies on the other arm's side: that arm
  is the further of two that both fall short. Larger than ``unused_arm``, so
  the hand used last is not sent across the table for it.
- ``never``: relative to the object the commanding hand holds (DESIGN.md:
  never its landmark); no words outweigh it.
- ``impossible``: the command cannot make sense in this state (open an open
  hand, close a closed or holding one, place with an empty hand, pick up with
  a full hand, stop while idle, execute while executing, switch past the
  first or last action).

Language P(L|C,S) (weights of matched words; verbs weigh most for choosing the
command, adjectives most for choosing the object):

- ``beta`` turns the weighted word matches into a likelihood,
  P(L|C,S) ~ exp(beta * match). It is large enough that one adjective the
  user said (weight 1.0) outweighs an unreachability penalty, and one explicit
  arm word outweighs an "impossible" penalty: what the user says explicitly
  wins, the prior decides what the user left out.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class PriorWeights:
    holding_move: float = -0.2
    novel_object: float = -0.5
    unused_arm: float = -0.5
    unreachable: float = -2.5
    impossible: float = -6.0
    never: float = -50.0  # a landmark the commanding hand holds: no words can make it one
    far_side: float = -0.5  # no hand used yet: the arm on the other side of the object
    middle_side: float = -0.1  # ... of an object in the middle (|y| within ``Margins.side_m``): a tie-breaker
    beyond_both: float = -1.0  # neither hand reaches it: the arm on the object's other side


@dataclass(frozen=True)
class LanguageWeights:
    verb: float = 3.0  # move, pick up, grab, place, point, ...
    option: float = 2.0  # above, up, clockwise, table, next, ...
    arm: float = 2.0  # right hand, left arm
    generic_arm: float = 0.3  # "your hand" without a side
    adjective: float = 1.0  # red, leftmost, biggest, tallest, middle
    noun: float = 0.7  # cup, box, plate, bowl
    generic_noun: float = 0.2  # object, thing, one
    anaphor: float = 1.0  # it, that, the same one
    number: float = 2.0  # "action 3"
    weak: float = 0.5  # a second reading of an ambiguous word ("left" as an arm)
    beta: float = 4.0


@dataclass(frozen=True)
class Margins:
    """How much an object must beat the runner-up to earn a salient label (paper III-G)."""

    location_m: float = 0.07  # leftmost/rightmost (y), nearest/farthest (x)
    height_m: float = 0.05  # tallest/shortest (z extent)
    volume_m3: float = 0.0005  # biggest/smallest
    side_m: float = 0.05  # |y| beyond which an object is on one arm's side (hand choice)


@dataclass(frozen=True)
class Decision:
    tie: float = 0.05  # log-score difference under which two commands tie
    max_candidates: int = 8  # candidates listed in a clarification
    typo_edits_short: int = 1  # edits (incl. swapped letters) tolerated in a word of up to 5 letters
    typo_edits_long: int = 2  # ... and in a longer word
    # a single command chosen with less of the probability mass than this is asked about ("Did you mean: ...?");
    # below every command of the corpus read right
    confirm_below: float = 0.05


PRIOR = PriorWeights()
LANGUAGE = LanguageWeights()
MARGINS = Margins()
DECISION = Decision()
