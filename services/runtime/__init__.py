"""The Zenoh runtime every service uses: session, typed pub/sub, health, liveliness, shutdown."""

from services.runtime.codec import DecodeError, decode, encode, encoding_for
from services.runtime.config import (
    DEFAULT_CONNECT,
    BusSettings,
    ConfigError,
    Credentials,
    RouterSecurity,
    client_config,
    default_keys_dir,
    default_state_dir,
    find_credentials,
    parse_endpoints,
    router_config,
)
from services.runtime.logs import configure_logging, get_logger
from services.runtime.service import (
    PARENT_ENV,
    Counters,
    ServiceContext,
    SessionRefused,
    SessionStopped,
    TypedPublisher,
    open_session,
    run_service,
)

__all__ = [
    "DEFAULT_CONNECT",
    "PARENT_ENV",
    "BusSettings",
    "ConfigError",
    "Credentials",
    "RouterSecurity",
    "Counters",
    "DecodeError",
    "ServiceContext",
    "SessionRefused",
    "SessionStopped",
    "TypedPublisher",
    "client_config",
    "default_keys_dir",
    "default_state_dir",
    "find_credentials",
    "configure_logging",
    "decode",
    "encode",
    "encoding_for",
    "get_logger",
    "open_session",
    "parse_endpoints",
    "router_config",
    "run_service",
]
