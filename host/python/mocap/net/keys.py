"""CURVE keys of the system's streams (ZeroMQ's CurveZMQ: authenticated and encrypted).

Each device that publishes (a camera box, the IMU hub, the live calibrator, `mocap replay`) and
the host have a key pair: `NAME.key` holds the secret key (40 characters of Z85, mode 0600, as
`mocap keys` writes it; its public key is derived from it) and `NAME.pub` the public key. The
publishers bind and are CURVE servers: a subscriber completes the handshake only with the server
holding the secret of the public key it expects on that endpoint, so a stranger publishing there
is refused. A server may also admit only the clients it knows (ZAP, `ServerKeys.allowed`).
Nothing here imports the host's error types: a bad key file raises KeyFileError (ValueError).
"""

from __future__ import annotations

import dataclasses
import os
import stat
import struct
from pathlib import Path

import zmq
from zmq.utils import z85

KEY_CHARS = 40  # Z85 of a 32-byte key
SECRET_SUFFIX, PUBLIC_SUFFIX = ".key", ".pub"


class KeyFileError(ValueError):
    pass


def is_key(text: object) -> bool:
    """True for 40 characters of Z85 that decode to a 32-byte key."""
    if not isinstance(text, str) or len(text) != KEY_CHARS:
        return False
    try:
        return len(z85.decode(text.encode("ascii"))) == 32
    except (ValueError, KeyError, struct.error):  # a character outside Z85, or a group past 2^32
        return False


@dataclasses.dataclass(frozen=True)
class KeyPair:
    public: str  # Z85
    secret: str  # Z85


def make_keypair(out_dir: str | Path, name: str, force: bool = False) -> tuple[Path, Path]:
    """Writes a new key pair as out_dir/NAME.key (secret, 0600) and NAME.pub; refuses to
    replace an existing secret key unless force. Returns (secret file, public file)."""
    if not name or "/" in name or name.startswith("."):
        raise KeyFileError(f"device name {name!r}: a plain file name")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    secret_path, public_path = out / (name + SECRET_SUFFIX), out / (name + PUBLIC_SUFFIX)
    if secret_path.exists() and not force:
        raise KeyFileError(f"{secret_path} exists: a device's key is made once (--force to replace it)")
    public, secret = zmq.curve_keypair()
    secret_path.unlink(missing_ok=True)
    fd = os.open(secret_path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "w") as f:
        f.write(secret.decode() + "\n")
    public_path.write_text(public.decode() + "\n")
    return secret_path, public_path


def read_secret(path: str | Path) -> KeyPair:
    """The key pair of a secret key file; refused when group or others may read it."""
    path = Path(path)
    try:
        mode = path.stat().st_mode
        text = path.read_text().strip()
    except OSError as e:
        raise KeyFileError(f"cannot read secret key {path}: {e.strerror}") from None
    except UnicodeDecodeError:
        raise KeyFileError(f"{path} is not a secret key (40 characters of Z85, as `mocap keys` writes)") from None
    if mode & (stat.S_IRWXG | stat.S_IRWXO):
        raise KeyFileError(f"secret key {path} is readable by others (mode {stat.S_IMODE(mode):04o}): chmod 600 it")
    if not is_key(text):
        raise KeyFileError(f"{path} is not a secret key (40 characters of Z85, as `mocap keys` writes)")
    return KeyPair(zmq.curve_public(text.encode()).decode(), text)


def read_public(text_or_path: str) -> str:
    """A public key given as its 40 characters or as a .pub file."""
    if is_key(text_or_path):
        return text_or_path
    try:
        text = Path(text_or_path).read_text().strip()
    except (OSError, UnicodeDecodeError):
        raise KeyFileError(f"{text_or_path!r} is neither a public key (40 characters of Z85) nor a key file") from None
    if not is_key(text):
        raise KeyFileError(f"{text_or_path} does not hold a public key (40 characters of Z85)")
    return text


@dataclasses.dataclass(frozen=True)
class ServerKeys:
    """A publisher's CURVE identity; allowed: the client keys it admits (None: any client that
    knows its public key)."""
    pair: KeyPair
    allowed: frozenset[str] | None = None


@dataclasses.dataclass(frozen=True)
class ClientKeys:
    """A subscriber's CURVE identity and the server key it expects on each endpoint (default:
    on any endpoint not listed; None: such an endpoint is an error)."""
    pair: KeyPair
    servers: dict[str, str]  # endpoint -> public key (Z85)
    default: str | None = None

    def server(self, endpoint: str) -> str:
        if endpoint not in self.servers and self.default is not None:
            return self.default
        if endpoint not in self.servers:
            raise KeyFileError(f"no key for {endpoint}: the session's curve keys do not list it")
        return self.servers[endpoint]
