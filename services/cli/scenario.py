"""Scenarios: timed "say" and "show" steps with the outcomes expected of the robot (YAML files).

    name: example
    description: Stand up, see an X, refuse to walk
    steps:
      - say: stand                      # spoken to the voice service as synthesised audio
        expect: {heard: stand, verdict: obey, action: stand_up, posture: standing}
      - say: go                         # an unsure "go" makes the robot ask; the person then says "yes"
        confirm: "yes"
        expect: {heard: go, action: walk_forward, posture: walking}
      - show: X                         # held up in front of the (synthetic) camera
        expect: {situation: danger}
      - wait: 1.0                       # a pause, in seconds
      - send: go                        # a VoiceCommand published directly, as `hri send command`
                                        # would: the recogniser is bypassed, and the timeline says so
        expect: {heard: go, verdict: refuse, reason: danger_sign, no_action: true,
                 said: "Sorry, I cannot do it."}

(`send` is for tests and for what the recogniser should not be asked to hear; the built-in scenarios
speak every command, "go" and "why" included, through the voice service.)

Every field of `expect` is optional; a step without `expect` only has to happen.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Self

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from schemas.messages import Action, Command, Posture, Reason, Shape, Situation, Verdict


class ScenarioError(ValueError):
    """A scenario file that cannot be used; the message names the file and the problem."""


class Expect(BaseModel):
    model_config = ConfigDict(extra="forbid")

    heard: Command | None = Field(default=None, description="what the voice service must recognise")
    verdict: Verdict | None = None
    reason: Reason | None = None
    action: Action | None = Field(default=None, description="the motion goal the decision sends")
    no_action: bool = Field(default=False, description="the decision must send no motion goal")
    situation: Situation | None = None
    posture: Posture | None = Field(default=None, description="the robot's posture once it settles")
    said: str | None = Field(default=None, description="text the robot must speak (substring)")


class Step(BaseModel):
    model_config = ConfigDict(extra="forbid")

    say: str | None = Field(default=None, description="words spoken to the robot")
    confirm: str | None = Field(
        default=None, description="with say or show: the answer spoken if the robot asks back (verdict ask: an "
                                  "unsure \"go\", or the O after an unsure \"go\" was refused); the verdict, reason "
                                  "and motion are then checked on the answer's decision")
    send: Command | None = Field(
        default=None, description="a command published as a VoiceCommand, bypassing the recogniser"
    )
    show: str | None = Field(default=None, description="X, O, TRIANGLE or none")
    wait: float | None = Field(default=None, ge=0, le=600)
    expect: Expect | None = None
    timeout: float = Field(default=15.0, gt=0, le=600, description="seconds to wait for the outcome")
    note: str | None = None

    @model_validator(mode="after")
    def _one_kind(self) -> Self:
        kinds = [k for k in ("say", "send", "show", "wait") if getattr(self, k) is not None]
        if len(kinds) != 1:
            raise ValueError(f"a step has exactly one of say, send, show, wait (got {kinds or 'none'})")
        if self.show is not None and self.show.upper() not in {s.value for s in Shape} | {"NONE"}:
            raise ValueError(f"show must be X, O, TRIANGLE or none, not {self.show!r}")
        if self.say is not None and not self.say.strip():
            raise ValueError("say needs words")
        if self.confirm is not None and ((self.say is None and self.show is None) or not self.confirm.strip()):
            raise ValueError("confirm needs words, and a say or show step to answer")
        if self.wait is not None and self.expect is not None and self.expect.model_dump(exclude_defaults=True):
            keys = set(self.expect.model_dump(exclude_defaults=True))
            if keys - {"posture", "situation"}:
                raise ValueError("a wait step can only expect posture or situation")
        return self

    @property
    def shape(self) -> Shape | None:
        return None if self.show is None or self.show.upper() == "NONE" else Shape(self.show.upper())

    def label(self) -> str:
        answer = f' (if asked: "{self.confirm}")' if self.confirm else ""  # only a say or a show has one
        if self.say is not None:
            return f'say "{self.say}"{answer}'
        if self.send is not None:
            return f"send {self.send.value}"
        if self.show is not None:
            return f"show {self.show.upper() if self.shape else 'nothing'}{answer}"
        return f"wait {self.wait:g} s"


class Scenario(BaseModel):
    model_config = ConfigDict(extra="forbid")

    name: str
    description: str = ""
    steps: list[Step] = Field(min_length=1)


def builtin_names() -> list[str]:
    return sorted(p.name[:-5] for p in resources.files("services.cli.scenarios").iterdir()
                  if p.name.endswith(".yaml"))


def load(source: str | Path) -> Scenario:
    """A built-in scenario by name (`paper`) or a YAML file by path."""
    path = Path(source)
    if not path.exists() and str(source) in builtin_names():
        text = resources.files("services.cli.scenarios").joinpath(f"{source}.yaml").read_text()
        where = f"built-in scenario {source!r}"
    elif path.is_file():
        text = path.read_text()
        where = str(path)
    else:
        raise ScenarioError(f"no scenario {str(source)!r}: give a YAML file or one of {', '.join(builtin_names())}")
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise ScenarioError(f"{where}: not valid YAML: {exc}") from None
    try:
        return Scenario.model_validate(data)
    except ValidationError as exc:
        lines = [f"  {_where(e['loc'])}: {e['msg']}" for e in exc.errors()]
        raise ScenarioError(f"{where}: invalid scenario:\n" + "\n".join(lines)) from None


def _where(loc: tuple[int | str, ...]) -> str:
    """A validation error's place, with steps counted from 1 as the demo counts them: `step 1, send`."""
    if len(loc) >= 2 and loc[0] == "steps" and isinstance(loc[1], int):
        rest = ".".join(str(p) for p in loc[2:])
        return f"step {loc[1] + 1}" + (f", {rest}" if rest else "")
    return ".".join(str(p) for p in loc)
