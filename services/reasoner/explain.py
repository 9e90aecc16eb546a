"""The words of an explanation. The agent chooses the explanation (its `template`) and recalls
the evidence from its episodic memory (agent/65_explain.soar, 66_explanations.soar); this module
only fills one sentence per template with the mark, the command and how long ago, and builds
the `Explanation` message that the `reasoner/explain` queryable answers with."""

from __future__ import annotations

import time

from schemas.messages import Action, Command, Decision, Evidence, Explanation, Reason, Situation, Verdict
from services.reasoner.agent_host import DecisionOutput, EvidenceOutput, ExplanationOutput

TEMPLATES: dict[str, str] = {
    "nothing": "I have not decided anything yet.",
    "refused-danger": "I saw {mark} {ago}, and no O since. Show me an O and I will walk.",
    "stopped-danger": "I stopped because I saw {mark} {ago}.",
    "danger-seen": "I saw {mark} {ago}. I will not walk until I see an O.",
    "safe-seen": "I saw an O {ago}, so it is safe to walk again.",
    "resumed": "I saw an O, so I carried out the 'go' you gave me {cause_ago}.",
    "obeyed": "You told me to {word} {ago}.",
    "confirmed": "I asked whether to walk, and you said yes {ago}.",
    "declined": "I asked whether to walk, and you said no {ago}.",
    "asked": "I was not sure I heard '{word}', so I asked first.",
    "asked-after-unclear": "You said something I did not understand just before '{word}', so I asked first.",
    "timed-out": "I asked whether to {word}, and you did not answer.",
    "already-done": "I had already done that when you said '{word}'.",
    "busy": "I was still moving when you said '{word}': that must finish first.",
    "not-understood": "I did not understand what you said.",
}
"""One sentence per explanation the agent can choose."""

MARK_NAMES = {"X": "an X mark", "TRIANGLE": "a triangle", "O": "an O"}
WORDS = {"stand": "stand up", "down": "sit down", "yes": "nod", "no": "shake my head"}
"""How a command reads after "told me to"."""


def ago(stamp: float | None, now: float) -> str:
    if stamp is None:
        return "before"
    seconds = max(0, round(now - stamp))
    if seconds < 2:
        return "just now"
    if seconds < 120:
        return f"{seconds} seconds ago"
    minutes = round(seconds / 60)
    return f"{minutes} minutes ago" if minutes < 120 else f"{round(minutes / 60)} hours ago"


def _first(evidence: tuple[EvidenceOutput, ...], role: str, kind: str, meaning: str | None = None
           ) -> EvidenceOutput | None:
    return next((e for e in evidence
                 if e.role == role and e.kind == kind and (meaning is None or e.meaning == meaning)), None)


def render(out: ExplanationOutput, now: float) -> str:
    """The sentence the robot says. An unknown template is the agent's error: ValueError."""
    if out.template not in TEMPLATES:
        raise ValueError(f"the agent chose an unknown explanation {out.template!r}")
    decision = out.decision
    word = decision.command if decision is not None and decision.command else "that"
    role = "cause" if out.template == "refused-danger" else "decision"
    meaning = "danger" if out.template.endswith("danger") or out.template == "danger-seen" else None
    mark = _first(out.evidence, role, "mark", meaning)
    heard = _first(out.evidence, "decision", "command")
    cause_heard = _first(out.evidence, "cause", "command")
    # A sentence about a mark says when the mark was seen; one about a command, when it was heard.
    # (A mark no longer in the store, after a rotation, is "a danger sign" seen "before".)
    about_mark = out.template in ("refused-danger", "stopped-danger", "danger-seen", "safe-seen")
    own = mark if about_mark else heard
    fields = {
        "word": WORDS.get(word, word) if out.template == "obeyed" else word,
        "mark": MARK_NAMES.get(mark.what, f"a {mark.what}") if mark is not None else "a danger sign",
        "ago": ago(own.stamp if own is not None else None, now),
        "cause_ago": ago(cause_heard.stamp, now) if cause_heard is not None else "before",
    }
    text = TEMPLATES[out.template].format(**fields)
    if out.template == "not-understood" and decision is not None and decision.command:
        text = f"I was not sure I heard '{decision.command}'."
    return text


def _decision_model(d: DecisionOutput) -> Decision:
    return Decision(
        stamp=d.cause_stamp if d.cause_stamp is not None else time.time(),  # made when its cause came in
        command=Command(d.command) if d.command else None, verdict=Verdict(d.verdict),
        reason=Reason(d.reason),
        action=Action(d.action) if d.action else None, situation=Situation(d.situation), say=d.say,
        cause_stamp=d.cause_stamp,
    )


def explanation_model(out: ExplanationOutput, text: str, now: float) -> Explanation:
    """The structured answer: the decision explained, its reason, the evidence and the episode."""
    decision = _decision_model(out.decision) if out.decision is not None else None
    return Explanation(
        decision=decision,
        reason=decision.reason if decision is not None else None,
        text=text,
        evidence=[
            Evidence(kind=e.kind, what=e.what, stamp=e.stamp or 0.0, episode=e.episode,
                     ago_s=round(max(0.0, now - e.stamp), 3) if e.stamp is not None else None)
            for e in out.evidence
        ],
        episode=out.episode,
    )
