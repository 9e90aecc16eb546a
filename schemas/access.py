"""Who may do what on the bus: the ownership half of the wire contract (DESIGN.md, key table and
safety invariant 6), and the Zenoh `access_control` rules generated from it.

`ACCESS` is the one table. Each row names a key (relative to `hri/<robot>/`), what kind of thing
lives there (a topic, a queryable or a liveliness token), who owns it (may put / serve / hold the
token) and who reads it (may subscribe / query / watch). The router's rules are generated from
this table by `access_control()`, so the contract and the access rules cannot drift apart.

Identities: the five services, `observer` (read-only: `hri status`, `hri spy`, `hri record`,
zenoh-cli) and `operator` (a person testing by hand: `hri send`, the demo's scenario runner,
`hri replay`). The operator reads what the observer reads; its writes (rows that name it as an
owner) are granted or withheld per deployment (`operator_writes`).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import Any

from schemas.keys import SERVICES, validate_robot_id

OBSERVER = "observer"
OPERATOR = "operator"
IDENTITIES: tuple[str, ...] = (*SERVICES, OBSERVER, OPERATOR)
"""Every identity a deployment has a secret for (`hri keys init` makes one per name)."""

READERS = (OBSERVER, OPERATOR)


class Kind(str, Enum):
    TOPIC = "topic"  # put / subscribe
    QUERYABLE = "queryable"  # declare_queryable + reply / query
    TOKEN = "token"  # liveliness token / liveliness subscriber and query


@dataclass(frozen=True)
class Access:
    """One row: `owners` put (topic), serve (queryable) or hold the token; `readers` subscribe,
    query or watch. `asked_as` lists wildcard forms under which owners are asked too (the
    router only matches a rule whose key expression includes the whole query key)."""

    key: str
    kind: Kind
    owners: tuple[str, ...]
    readers: tuple[str, ...] = ()
    asked_as: tuple[str, ...] = ()


HEALTH_ASKERS: dict[str, tuple[str, ...]] = {"speech": ("voice",)}
"""Services that ask another's health: the voice service asks the speech service's at start-up whether the robot is in
the middle of a sentence (`speaking`), not to answer its own voice, and as each sentence begins its espeak-ng voice
and rate, to render the sentence again as its echo canceller's reference."""


def _per_service() -> tuple[Access, ...]:
    # A service may also ask after itself: a container's health check (`hri status --service`) runs
    # with the only identity mounted there, the service's own.
    rows: list[Access] = []
    for name in SERVICES:
        readers = (*READERS, name, *HEALTH_ASKERS.get(name, ()))
        rows.append(Access(f"{name}/health", Kind.QUERYABLE, (name,), readers, asked_as=("*/health",)))
        rows.append(Access(f"alive/{name}", Kind.TOKEN, (name,), (name,)))
    return tuple(rows)


ACCESS: tuple[Access, ...] = (
    # topics: the key table of DESIGN.md
    Access("vision/marks", Kind.TOPIC, ("vision", OPERATOR), ("reasoner",)),
    Access("vision/scene", Kind.TOPIC, (OPERATOR,), ("vision",)),  # simulator control
    Access("vision/preview", Kind.TOPIC, ("vision",)),
    Access("voice/command", Kind.TOPIC, ("voice", OPERATOR), ("reasoner",)),
    # voice: the answer to its last command, before it puts the next (services/voice/pacing.py): the router's rate
    # limit below drops a put that reaches it within 1 ms of the last, as puts held back together would
    Access("reasoner/decision", Kind.TOPIC, ("reasoner",), ("voice",)),
    Access("motion/goal", Kind.TOPIC, ("reasoner",), ("motion",)),
    Access("motion/state", Kind.TOPIC, ("motion",), ("reasoner",)),
    Access("motion/joints", Kind.TOPIC, ("motion",)),
    Access("speech/say", Kind.TOPIC, ("reasoner",), ("speech",)),
    Access("speech/state", Kind.TOPIC, ("speech",), ("reasoner", "voice")),  # voice: not to answer its own voice
    # the observer and the operator read every topic of the robot
    Access("**", Kind.TOPIC, (), READERS),
    # queryables: the Soar command line can change the agent, so only the operator asks it
    Access("reasoner/soar", Kind.QUERYABLE, ("reasoner",), (OPERATOR,)),
    Access("reasoner/explain", Kind.QUERYABLE, ("reasoner",), READERS),
    *_per_service(),
    # liveliness: motion stops a walk when the reasoner's token goes (safety invariant 3)
    Access("alive/reasoner", Kind.TOKEN, (), ("motion",)),
    Access("alive/**", Kind.TOKEN, (), READERS),
)

# (kind, side) -> [(messages, flow)] in Zenoh's access-control vocabulary. A subscriber needs
# the router to let it declare (ingress) and to send it the puts (egress); a queryable is sent the
# queries (egress) and answers (ingress); a watcher is sent the tokens (egress).
_MESSAGES: dict[tuple[Kind, str], tuple[tuple[tuple[str, ...], str], ...]] = {
    (Kind.TOPIC, "owner"): ((("put",), "ingress"),),
    (Kind.TOPIC, "reader"): ((("declare_subscriber",), "ingress"), (("put",), "egress")),
    (Kind.QUERYABLE, "owner"): ((("declare_queryable", "reply"), "ingress"), (("query",), "egress")),
    (Kind.QUERYABLE, "reader"): ((("query",), "ingress"), (("reply",), "egress")),
    (Kind.TOKEN, "owner"): ((("liveliness_token",), "ingress"),),
    (Kind.TOKEN, "reader"): (
        (("declare_liveliness_subscriber", "liveliness_query"), "ingress"),
        (("liveliness_token",), "egress"),
    ),
}
# Every identity learns which subscribers and queryables exist on its robot's keys: a Zenoh client
# only sends a put that it knows a subscriber for, so the router, not the client, is where a denied
# put is dropped. Who subscribes to what is the public contract, nothing secret.
_DISCOVERY = (("declare_subscriber", "declare_queryable"), "egress")


def grants(identity: str, *, operator_writes: bool = True) -> dict[tuple[tuple[str, ...], str], list[str]]:
    """(messages, flow) -> relative key expressions this identity is allowed, from `ACCESS`."""
    out: dict[tuple[tuple[str, ...], str], list[str]] = {}
    for row in ACCESS:
        sides = []
        if identity in row.owners and (operator_writes or identity != OPERATOR):
            sides.append("owner")
        if identity in row.readers:
            sides.append("reader")
        for side in sides:
            for messages, flow in _MESSAGES[(row.kind, side)]:
                keys = out.setdefault((messages, flow), [])
                extra = row.asked_as if "query" in messages else ()
                for key in (row.key, *extra):
                    if key not in keys:
                        keys.append(key)
    out[_DISCOVERY] = ["**"]
    return out


def access_control(
    robot: str, *, tls: bool = False, operator_writes: bool = True, identities: tuple[str, ...] = IDENTITIES
) -> dict[str, Any]:
    """The router's `access_control` section for robot `robot`: deny by default, allow what the
    table grants. Subjects match a user name on plain TCP (which the router accepts on loopback
    only) and, with `tls`, the same user name *and* certificate common name on TLS links, so a
    stolen password without its certificate (or the reverse) is refused."""
    validate_robot_id(robot)
    prefix = f"hri/{robot}"
    rules: list[dict[str, Any]] = []
    subjects: list[dict[str, Any]] = []
    policies: list[dict[str, Any]] = []
    for identity in identities:
        rule_ids = []
        for (messages, flow), keys in grants(identity, operator_writes=operator_writes).items():
            rule_id = f"{identity}:{'+'.join(messages)}:{flow}"
            rules.append(
                {
                    "id": rule_id,
                    "permission": "allow",
                    "flows": [flow],
                    "messages": list(messages),
                    "key_exprs": [f"{prefix}/{k}" for k in keys],
                }
            )
            rule_ids.append(rule_id)
        ids = [f"{identity}@tcp"]
        subjects.append({"id": f"{identity}@tcp", "usernames": [identity], "link_protocols": ["tcp"]})
        if tls:
            ids.append(f"{identity}@tls")
            subjects.append(
                {
                    "id": f"{identity}@tls",
                    "usernames": [identity],
                    "cert_common_names": [identity],
                    "link_protocols": ["tls"],
                }
            )
        policies.append({"id": identity, "rules": rule_ids, "subjects": ids})
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }


def owners(key: str) -> tuple[str, ...]:
    """Who may put the topic `key` (relative to `hri/<robot>/`), per the table."""
    return tuple(o for row in ACCESS if row.kind is Kind.TOPIC and row.key == key for o in row.owners)


def may_put(identity: str, key: str, *, operator_writes: bool = True) -> bool:
    """Whether the table lets `identity` put the relative `key`."""
    return identity in owners(key) and (operator_writes or identity != OPERATOR)


RATE_LIMITS: dict[str, float] = {
    "voice/command": 1000.0,
    "vision/marks": 200.0,
}
"""Puts a second that one session may make on the reasoner's inputs (keys relative to
`hri/<robot>/`); the router drops the rest on arrival (Zenoh downsampling, per session), so a flood
from an allowed identity (a bug, a stolen password) is cut to this before it reaches the reasoner or
anyone else's link. Downsampling drops any put that comes sooner than 1/rate after the last one let
through, whatever it says, so the limits sit far above what a real publisher does: the voice service
puts once per utterance, and a command that answers a question follows the question spoken aloud (the
decision alone can come back within a millisecond of the command that caused it); a camera gives some tens of frames a second, and a mark observation
only repeats the state of the one before. Motion goals, the reasoner's outputs and the simulator's
scene are not limited: a stop must never be dropped, and the operator may change the scene twice in
a millisecond."""


INPUT_PRIORITIES: dict[str, str] = {
    "voice/command": "data",
    "vision/scene": "data",
    "vision/marks": "interactive_high",
}
"""The Zenoh priority the router gives every put on the reasoner's inputs (and the simulator's
scene), whatever the publisher asked for: a danger sign travels above commands, and no publisher of
a command can claim a priority above the marks' (the stop goal's `real_time`, for one)."""


def qos_overwrites(robot: str) -> list[dict[str, Any]]:
    """The router's `qos/network` section for robot `robot`, from `INPUT_PRIORITIES`."""
    validate_robot_id(robot)
    return [
        {
            "id": f"hri-priority-{key.replace('/', '-')}",
            "messages": ["put"],
            "flows": ["ingress"],
            "key_exprs": [f"hri/{robot}/{key}"],
            "overwrite": {"priority": priority},
        }
        for key, priority in INPUT_PRIORITIES.items()
    ]


def downsampling(robot: str) -> list[dict[str, Any]]:
    """The router's `downsampling` section for robot `robot`, from `RATE_LIMITS`."""
    validate_robot_id(robot)
    return [
        {
            "id": "hri-input-rates",
            "flows": ["ingress"],
            "messages": ["put"],
            "rules": [{"key_expr": f"hri/{robot}/{key}", "freq": freq} for key, freq in RATE_LIMITS.items()],
        }
    ]
