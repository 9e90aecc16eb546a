"""The Soar debugger's way in: a remote SML connection to the live agent, only when asked for.

Both ends run in their own processes (one Soar kernel per process): the agent's owner thread, as
the reasoner runs it, and a client that connects as the Soar Java debugger would.
"""

from __future__ import annotations

import subprocess
import sys

from services.cli.router import free_port
from tests.conftest import ROOT

AGENT = """
import sys, time
from services.reasoner.agent_host import AgentConfig, Memory
from services.reasoner.driver import AgentDriver
from services.runtime import get_logger
port = None if sys.argv[1] == "none" else int(sys.argv[1])
driver = AgentDriver(AgentConfig(debugger_port=port), Memory(situation="danger"), lambda out: None,
                     get_logger("reasoner"))
driver.start()
print("ready", flush=True)
sys.stdin.readline()
driver.stop()
"""

CLIENT = """
import sys
import soar_sml as sml
kernel = sml.Kernel.CreateRemoteConnection(True, "127.0.0.1", int(sys.argv[1]))
if kernel.HadError():
    print("no connection:", kernel.GetLastErrorDescription())
    sys.exit(3)
agent = kernel.GetAgentByIndex(0)
print(agent.GetAgentName())
print(agent.ExecuteCommandLine("print s1"))
kernel.Shutdown()
"""


def _with_agent(port: str, client_port: int) -> subprocess.CompletedProcess[str]:
    agent = subprocess.Popen([sys.executable, "-c", AGENT, port], cwd=ROOT, text=True,
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    try:
        assert agent.stdout is not None and agent.stdout.readline().strip() == "ready"
        return subprocess.run([sys.executable, "-c", CLIENT, str(client_port)], cwd=ROOT, text=True,
                              capture_output=True, timeout=30)
    finally:
        agent.communicate("stop\n", timeout=20)
        assert agent.returncode == 0


def test_a_debugger_attaches_to_the_live_agent_when_a_port_is_given() -> None:
    port = free_port()
    client = _with_agent(str(port), port)
    assert client.returncode == 0, client.stdout + client.stderr
    name, state = client.stdout.split("\n", 1)
    assert name == "hri"
    assert "^situation danger" in state  # the restored memory of the live agent, read remotely


def test_no_listener_without_a_port() -> None:
    client = _with_agent("none", 12121)  # not even on SML's default port
    assert client.returncode == 3, client.stdout + client.stderr
