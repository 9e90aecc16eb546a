"""Client side of `python -m services.reasoner soar "<command>"`: ask the live agent over Zenoh."""

from __future__ import annotations

from schemas.keys import Keys
from services.runtime import BusSettings, ConfigError, get_logger, open_session


def query_soar(
    command: str, *, robot: str | None, connect: str | None, timeout: float
) -> tuple[int, str, str]:
    """Returns (exit code, stdout text, stderr text): 0 answered, 1 Soar error or no answer, 2 no bus."""
    try:
        settings = BusSettings.from_env(robot=robot, connect=connect)
    except ConfigError as exc:
        return 2, "", f"configuration error: {exc}"
    key = Keys(settings.robot).reasoner_soar
    try:
        session = open_session(settings, get_logger("reasoner-cli"), attempts=1)
    except Exception as exc:
        first_line = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        return 2, "", f"cannot reach the zenoh router at {','.join(settings.connect)}: {first_line}"
    try:
        outputs: list[str] = []
        errors: list[str] = []
        for reply in session.get(key, payload=command, timeout=timeout):
            if reply.ok is not None:
                outputs.append(reply.ok.payload.to_string())
            elif reply.err is not None:
                errors.append(reply.err.payload.to_string())
    finally:
        session.close()
    if not outputs and not errors:
        return 1, "", (f"no reasoner answered on {key} within {timeout:g} s: is "
                       f"`python -m services.reasoner` running for robot '{settings.robot}' on "
                       f"{','.join(settings.connect)}?")
    return (1 if errors else 0), "\n".join(outputs), "\n".join(errors)
