"""The simulated OP2 bus: `SimBus` serves a CM-740 and twenty MX-28s on a pseudo-terminal."""

from services.motion.simbus.bus import BusStats, SimBus
from services.motion.simbus.devices import CM740, MX28

__all__ = ["CM740", "MX28", "BusStats", "SimBus"]
