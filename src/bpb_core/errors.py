"""Exception types shared by the core, the plugins and the CLI.

Every error a user can cause carries a one-line message that names the file or field at fault.
The CLI maps them to exit codes: :class:`BadInput` and :class:`WriteRefused` are 2, anything
else unexpected is 3.
:class:`Notice` is the warning a plugin gives about slow work the user did not ask for.
"""

from __future__ import annotations

import errno
import importlib
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from types import ModuleType
from typing import Self


class BpbError(Exception):
    """Base class of every error bpb raises on purpose."""

    exit_code = 3
    option: str | None = None
    """The plugin option whose value the error is about (``dt``), as the plugin takes it; set by
    :meth:`about` (a caller that adds context in front keeps it). The plugin cannot know where
    its user set it (a flag, a config field, a library call): a caller that does names that
    place (:meth:`naming`)."""

    @classmethod
    def about(cls, option: str, detail: str) -> Self:
        """An error about the value of the plugin's ``option``: ``"dt: <detail>"``."""
        error = cls(f"{option}: {detail}")
        error.option = option
        return error

    def naming(self, names: Mapping[str, str]) -> str:
        """The message with the option it starts with named as in ``names`` (``{"dt": "--dt"}``:
        how the caller's user sets it); unchanged when it is about no option in ``names``."""
        text, option = str(self), self.option
        if option is None or option not in names or not text.startswith(f"{option}: "):
            return text
        return names[option] + text.removeprefix(option)


class BadInput(BpbError):
    """The user gave something bpb cannot use: a file, a field, an option (exit code 2)."""

    exit_code = 2


def need_module(name: str, what: str, install: str) -> ModuleType:
    """``import name`` for ``what`` (a command or component), or a :class:`BadInput` saying
    what needs the module and how to install it (``install``, e.g. ``pip install 'bpb[report]'``),
    so a missing optional package is one line and exit 2, never an internal error.

    Raises:
        BadInput: The module (or a part of it) cannot be imported.
    """
    try:
        return importlib.import_module(name)
    except ImportError as exc:
        raise BadInput(f"{what} needs {exc.name or name}: {install}") from None


class WriteRefused(BpbError):
    """The system refused to write a file bpb was making (a full disk, a quota, a file size
    limit): the user's environment, not a bug in bpb, so exit code 2, as for an ``--out`` found
    not writable before the work starts. Not a :class:`BadInput`: code that drops or blames the
    work on bad input (a config whose scenes cannot be made) must not take it for that."""

    exit_code = 2


NO_ROOM = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG})
"""The ``errno`` of a write refused for want of room: a full disk, a quota, a file size limit."""


class Interrupted(KeyboardInterrupt):
    """Ctrl-C stopped a command that leaves something behind; the message says what is left
    where (``bpb`` prints ``aborted; <message>`` and exits 130). A ``KeyboardInterrupt``, so a
    library caller that catches Ctrl-C catches this too."""


def write_refused(path: object, exc: OSError) -> WriteRefused:
    """``PATH: cannot write: [Errno 28] No space left on device`` for ``exc`` raised writing
    ``path`` (or the file ``exc`` names, when a write under the folder ``path`` raised it)."""
    named = exc.filename if exc.filename is not None else path
    reason = f"[Errno {exc.errno}] {exc.strerror}" if exc.errno is not None else str(exc)
    return WriteRefused(f"{named}: cannot write: {reason}")


@contextmanager
def writing(path: object) -> Iterator[None]:
    """Write ``path`` in the block; an ``OSError`` leaves as :func:`write_refused`'s one line.

    A failed ``write()`` names no file (``[Errno 27] File too large``); only its caller knows
    which one it was writing."""
    try:
        yield
    except OSError as exc:
        raise write_refused(path, exc) from None


class UnknownName(BadInput):
    """A task, adapter, simulator, scorer or scene family name that no plugin registered."""

    def __init__(self, kind: str, name: str, known: Iterable[str]) -> None:
        self.kind = kind
        self.name = name
        self.known = sorted(known)
        listed = ", ".join(self.known) or "none installed"
        plural = f"{kind[:-1]}ies" if kind.endswith("y") else f"{kind}s"  # scene families
        super().__init__(f"unknown {kind} {name!r}; known {plural}: {listed}")


class UnknownScene(BadInput, KeyError):
    """``dataset[scene_id]`` for an id the dataset's selection does not hold. A ``KeyError``
    (so ``except KeyError`` works) whose message names the folder, the id and how to list ids."""

    def __init__(self, root: object, scene_id: object, example: str | None) -> None:
        self.scene_id = scene_id
        like = f" (ids look like {example})" if example else " (it holds no scene)"
        super().__init__(
            f"{root}: no scene {scene_id!r} in the dataset's selection{like}; list them with "
            "[scene.scene_id for scene in dataset]"
        )

    def __str__(self) -> str:  # KeyError's would show the message in quotes
        return str(self.args[0])


class PluginError(BpbError):
    """The plugin set is inconsistent (two plugins claim one name, a misspelt hook, a hook
    returning something other than its records)."""

    exit_code = 2


class PluginBug(PluginError):
    """A plugin's code raised or broke its contract: a bug to report to the plugin, not bad
    input (exit code 3, like bpb's own bugs, but naming the plugin)."""

    exit_code = 3


class Notice(UserWarning):
    """A one-line note for the user, given with :func:`warnings.warn` before something slow
    they did not ask for (a one-time build of a plugin's compiled code, say): the CLI prints it
    as a ``note:`` line on stderr, a library caller sees or filters an ordinary warning."""


def named(kind: str, component: object) -> str:
    """``task 'q1'``: how one-line plugin errors name a component of ``kind`` (by its ``name``,
    else its class)."""
    return f"{kind} {getattr(component, 'name', type(component).__name__)!r}"


@contextmanager
def blamed(origin: str, what: str, passing: tuple[type[Exception], ...] = ()) -> Iterator[None]:
    """Run plugin code; an unexpected exception leaves as a one-line :class:`PluginBug`
    naming the plugin (``origin``, e.g. ``Registered.origin``) and what it was doing.

    A :class:`BpbError` (a ``BadInput``, a ``ParseFailure``, a model error) and the ``passing``
    types (a ``ValueError`` naming a field, for some hooks) are the plugin's contract and pass
    through; a write refused for want of room (:data:`NO_ROOM`) leaves as :class:`WriteRefused`.
    """
    try:
        yield
    except BpbError:
        raise
    except Exception as exc:
        if isinstance(exc, passing):
            raise
        if isinstance(exc, OSError) and exc.errno in NO_ROOM:
            raise write_refused(f"{origin}: {what}", exc) from None
        raise PluginBug(f"{origin}: {what} raised {type(exc).__name__}: {exc}") from exc


class ParseFailure(BpbError):
    """A model reply holds no answer that validates against the task's schema."""

    def __init__(self, message: str, *, truncated: bool = False) -> None:
        self.truncated = truncated
        super().__init__(message)


class ModelError(BpbError):
    """A model call failed for a reason that is not the content of the answer."""

    retryable = False


class RetryableModelError(ModelError):
    """Infrastructure trouble worth another try: rate limit, 5xx, timeout, dropped connection."""

    retryable = True

    def __init__(self, message: str, *, retry_after: float | None = None) -> None:
        self.retry_after = retry_after
        super().__init__(message)


class RateLimited(RetryableModelError):
    """HTTP 429; ``retry_after`` carries the server's Retry-After in seconds when it sent one."""


class ServerError(RetryableModelError):
    """HTTP 5xx or a body that is not a valid response."""


class ModelTimeout(RetryableModelError):
    """The call did not finish within its timeout."""


class ConnectionFailure(RetryableModelError):
    """The connection could not be made or broke off."""


class SetupFailure(ModelError):
    """An error no retry can fix and every call of the adapter would meet: the model is not
    found, a parameter is invalid, the quota is spent, the key is refused, or the provider
    cannot be reached at all. The runner stops the adapter on its first occurrence (the
    other adapters of a sweep go on); ``bpb run`` exits 2.

    Args:
        cause: What is wrong, in a few words the one-line message leads with
            (``model not found``).
        message: The provider's own message (secrets redacted).
    """

    def __init__(self, cause: str, message: str = "") -> None:
        self.cause = cause
        super().__init__(f"{cause}: {message}" if message else cause)


class AuthenticationFailed(SetupFailure):
    """401/403: the key is missing, wrong, or not allowed to use the model."""


class RequestRejected(ModelError):
    """A 4xx about this request alone (its prompt too long for the context window, its content
    refused by a policy filter): retrying cannot help, but other requests may succeed."""
