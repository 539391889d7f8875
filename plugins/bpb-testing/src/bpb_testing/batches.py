"""Provider batch jobs on the fake server: what OpenAI's Batch API, Anthropic's Message Batches
and Gemini's batch mode share, each wire format in its own module (:mod:`bpb_testing.batch_openai`,
:mod:`bpb_testing.batch_anthropic`, :mod:`bpb_testing.batch_gemini`).

A job holds its requests in their provider's own body format and answers them with the same
replies, faults included, as the synchronous endpoints (:meth:`FakeOpenAI.plan` and
:func:`bpb_testing.protocols.reply_body`): a prompt the server knows is answered correctly, a
``scene/task`` key's fault plan is consumed one entry per request whether it arrives alone or in
a batch. In a batch an HTTP fault (``429``, ``500``, ``400``, ...; ``truncated`` and
``nonjson`` count as ``500``) becomes that request's error result, and ``hang`` a request that
is never answered, so that its batch runs until its completion window ends and expires with the
request unanswered.

Time is the server's clock, the wall clock plus an offset that ``POST /batch/clock`` with
``{"advance": SECONDS}`` moves on, so a test walks a batch through a day in milliseconds. A job
spends ``validating`` seconds validating, then answers its requests evenly over ``in_progress``
seconds (all at once when it is 0), ``finalizing`` seconds finalizing, and ends; it expires when
its window (24 h; Gemini 48 h) ends first. ``stall_after`` stops every job after that many
requests (a provider that falls behind: the job expires with the rest unanswered); ``plan``
gives per job, in the order they are created, ``{"stall_after": N}``, ``{"fail": "MESSAGE"}``
(the provider fails the whole job) or ``{"drop_reply": true}`` (the provider accepts the job and
the connection drops before its reply: a client killed between the provider accepting a batch
and recording it, which must find and adopt the job by listing). All are set under ``batch`` in
the server's config.

``GET /batch/stats`` says how often each ``custom_id`` was answered with a reply the provider
bills (``paid``; an error, a cancelled or an expired request is not billed) and how often it was
processed at all, and each job's state, so that a test can assert that no pair was paid twice.
"""

from __future__ import annotations

import itertools
import math
import time
from collections import Counter
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from aiohttp import web

from bpb_testing.fakereplies import HTTP_FAULTS, error_body, fault_reply, model_reply
from bpb_testing.protocols import anthropic_body, gemini_body, request_prompt, responses_body
from bpb_testing.rules import anthropic_rejection

if TYPE_CHECKING:
    from bpb_testing.fakeserver import FakeOpenAI

DAY = 86400.0
WINDOWS = {"openai": DAY, "anthropic": DAY, "gemini": 2 * DAY}
"""How long each provider lets a batch run before it expires (its documented window)."""

# Provider limits (documented) and the server's config keys that lower them for a test.
LIMITS = {
    "openai_requests": 50_000,  # per batch input file
    "openai_batch_bytes": 200 * 1024 * 1024,  # a batch input file
    "openai_file_bytes": 512 * 1024 * 1024,  # any uploaded file
    "anthropic_requests": 100_000,  # per Message Batch
    "anthropic_bytes": 256 * 1024 * 1024,  # a Message Batch create request
    "gemini_inline_bytes": 20 * 1024 * 1024,  # inline requests of one batch
    "gemini_file_bytes": 2 * 1024 * 1024 * 1024,  # an uploaded file
}
Handler = Callable[[web.Request], Awaitable[web.StreamResponse]]
_TRANSPORT = ("truncated", "nonjson")  # faults with no meaning inside a batch: a 500


@dataclass
class Entry:
    """One request of a job: its id in the batch, its protocol and body, and what became of
    it (``None`` until processed; ``hung`` when it is never answered)."""

    custom_id: str
    protocol: str  # openai-chat, openai-responses, anthropic or gemini
    body: dict[str, Any]
    result: dict[str, Any] | None = None  # {"status": 200, "body": ...} or an error
    hung: bool = False
    info: dict[str, Any] = field(default_factory=dict)  # what the provider echoes back

    @property
    def ok(self) -> bool:
        return self.result is not None and self.result["status"] == 200


@dataclass
class Job:
    """A provider batch and its state on the server's clock."""

    provider: str
    id: str
    entries: list[Entry]
    created: float
    info: dict[str, Any] = field(default_factory=dict)  # provider fields: endpoint, metadata...
    stall_after: int | None = None
    fail: str | None = None
    drop_reply: bool = False  # accepted, but the connection drops before the reply
    errors: list[dict[str, Any]] = field(default_factory=list)  # validation errors (failed)
    started: float | None = None  # validation over: in progress
    finalizing: float | None = None
    cancel_at: float | None = None
    ended: float | None = None
    outcome: str | None = None  # completed, expired, cancelled or failed once ended

    def counts(self) -> dict[str, int]:
        """How many requests succeeded, errored and are still unanswered."""
        done = [e for e in self.entries if e.result is not None]
        ok = sum(1 for e in done if e.ok)
        return {"total": len(self.entries), "ok": ok, "error": len(done) - ok,
                "pending": len(self.entries) - len(done)}  # fmt: skip

    def status(self) -> str:
        """The generic state: ``validating``, ``in_progress``, ``finalizing``,
        ``cancelling`` or the outcome."""
        if self.outcome is not None:
            return self.outcome
        if self.cancel_at is not None:
            return "cancelling"
        if self.finalizing is not None:
            return "finalizing"
        return "in_progress" if self.started is not None else "validating"


class BatchStore:
    """Every job and uploaded file of the fake server, moved on by its clock."""

    def __init__(self, server: FakeOpenAI, config: dict[str, Any]) -> None:
        self.server = server
        self.offset = 0.0
        self.jobs: dict[str, Job] = {}
        self.files: dict[str, dict[str, Any]] = {}
        self.paid: Counter[str] = Counter()
        self.processed: Counter[str] = Counter()
        self.created_jobs = 0
        self._ids = itertools.count(1)
        self.configure(config)

    def configure(self, config: dict[str, Any]) -> None:
        """Take the ``batch`` part of the server's config."""
        self.validating = float(config.get("validating", 0.0))
        self.in_progress = float(config.get("in_progress", 0.0))
        self.finalizing = float(config.get("finalizing", 0.0))
        self.cancelling = float(config.get("cancelling", 0.0))
        stall = config.get("stall_after")
        self.stall_after = None if stall is None else int(stall)
        self.plan: list[dict[str, Any]] = list(config.get("plan", []))
        self.limits = {k: int(config.get(k, v)) for k, v in LIMITS.items()}

    def now(self) -> float:
        """The server's clock."""
        return time.time() + self.offset

    def new_id(self, prefix: str) -> str:
        """A fresh id such as ``batch_fake0001``."""
        return f"{prefix}{next(self._ids):04d}"

    def add_job(self, provider: str, prefix: str, entries: list[Entry], **info: Any) -> Job:
        """Create a job (validating); the next entry of the job plan applies to it."""
        job = Job(provider, self.new_id(prefix), entries, self.now(), info)
        job.stall_after = self.stall_after
        if self.created_jobs < len(self.plan):
            step = self.plan[self.created_jobs]
            job.stall_after = step.get("stall_after", job.stall_after)
            job.fail = step.get("fail")
            job.drop_reply = bool(step.get("drop_reply", False))
        self.created_jobs += 1
        self.jobs[job.id] = job
        return job

    def job(self, provider: str, job_id: str) -> Job | None:
        """The job ``job_id`` of ``provider``, moved on to now."""
        job = self.jobs.get(job_id)
        if job is None or job.provider != provider:
            return None
        self.advance(job)
        return job

    def listed(self, provider: str) -> list[Job]:
        """The provider's jobs, newest first, moved on to now."""
        jobs = [j for j in self.jobs.values() if j.provider == provider]
        for job in jobs:
            self.advance(job)
        return sorted(jobs, key=lambda j: j.created, reverse=True)

    def cancel(self, job: Job) -> None:
        """Ask a running job to stop: unanswered requests are cancelled once ``cancelling``
        seconds have passed."""
        if job.outcome is None and job.cancel_at is None:
            job.cancel_at = self.now()
            self.advance(job)

    def advance(self, job: Job) -> None:
        """Move ``job`` on to the server's clock: validate, answer the requests due by now,
        end it (completed, expired, cancelled or failed)."""
        now = self.now()
        if job.outcome is not None:
            return
        start = job.created + self.validating
        if job.started is None:
            if now < start and (job.cancel_at is None or job.cancel_at >= start):
                return
            if job.cancel_at is not None and job.cancel_at < start:
                self._end(job, "cancelled", job.cancel_at + self.cancelling, now)
                return
            if job.errors or job.fail:
                if job.fail:
                    job.errors.append({"code": "failed", "message": job.fail})
                job.outcome, job.ended = "failed", start
                return
            job.started = start
        until = min(now, job.cancel_at) if job.cancel_at is not None else now
        self._answer_due(job, until)
        expires = job.created + WINDOWS[job.provider]
        if job.cancel_at is not None:
            self._end(job, "cancelled", job.cancel_at + self.cancelling, now)
            return
        waiting = [e for e in job.entries if e.result is None]
        if not waiting and job.finalizing is None:
            job.finalizing = min(now, job.started + self.in_progress)
        if job.finalizing is not None and now >= job.finalizing + self.finalizing:
            job.outcome, job.ended = "completed", job.finalizing + self.finalizing
        elif job.outcome is None and now >= expires:
            job.outcome, job.ended = "expired", expires

    def _end(self, job: Job, outcome: str, at: float, now: float) -> None:
        if now >= at:
            job.outcome, job.ended = outcome, at

    def _answer_due(self, job: Job, until: float) -> None:
        """Answer the requests due by ``until``: evenly over ``in_progress`` seconds, at most
        ``stall_after`` of them, never a hung one."""
        assert job.started is not None
        total = len(job.entries)
        elapsed = until - job.started
        if self.in_progress <= 0 or elapsed >= self.in_progress:
            due = total
        else:
            due = max(0, math.floor(total * elapsed / self.in_progress))
        if job.stall_after is not None:
            due = min(due, job.stall_after)
        for entry in job.entries[:due]:
            if entry.result is None and not entry.hung:
                self._answer(job, entry)

    def _answer(self, job: Job, entry: Entry) -> None:
        """Answer one request as the synchronous endpoint would."""
        self.processed[entry.custom_id] += 1
        if entry.protocol == "anthropic":
            rejected = anthropic_rejection(entry.body)
            if rejected is not None:
                error = {"type": "invalid_request_error", "message": rejected}
                entry.result = {"status": 400, "error": {"type": "error", "error": error}}
                return
        _, fault, answer = self.server.plan(*request_prompt(entry.protocol, entry.body))
        if fault == "hang":
            entry.hung = True
            return
        fault = "500" if fault in _TRANSPORT else fault
        if fault in HTTP_FAULTS:
            wire = {"anthropic": "anthropic", "gemini": "gemini"}.get(entry.protocol, "openai")
            status = int(HTTP_FAULTS[fault]["status"])
            entry.result = {"status": status, "error": error_body(fault, wire)}
            return
        model = str(job.info.get("model", "fake"))
        entry.result = {"status": 200, "body": reply_body(entry, fault, answer, model)}
        self.paid[entry.custom_id] += 1

    def stats(self) -> dict[str, Any]:
        """``GET /batch/stats``: answers per ``custom_id`` and every job's state."""
        for job in self.jobs.values():
            self.advance(job)
        return {
            "paid": dict(self.paid),
            "processed": dict(self.processed),
            "jobs": {
                j.id: {"provider": j.provider, "status": j.status(), **j.counts()}
                for j in self.jobs.values()
            },
            "files": len(self.files),
            "clock": self.now(),
        }


async def created(request: web.Request, job: Job, body: dict[str, Any]) -> web.StreamResponse:
    """The reply to a create call: ``body``, or with ``drop_reply`` a cut connection."""
    if job.drop_reply:
        dropped = await fault_reply(request, "truncated", 0.0)
        assert dropped is not None
        return dropped
    return web.json_response(body)


def reply_body(entry: Entry, fault: str, answer: str, model: str) -> dict[str, Any]:
    """The 200 reply to a batch request, the synchronous endpoint's body."""
    if entry.protocol == "openai-chat":
        return model_reply(entry.body.get("model", model), fault, answer)
    if entry.protocol == "openai-responses":
        return responses_body(entry.body, fault, answer)
    if entry.protocol == "anthropic":
        return anthropic_body(entry.body, fault, answer)
    return gemini_body(model.removeprefix("models/"), fault, answer)


def add_batch_routes(app: web.Application, server: FakeOpenAI) -> None:
    """The three providers' batch endpoints and the control routes ``GET /batch/stats`` and
    ``POST /batch/clock``."""
    from bpb_testing import batch_anthropic, batch_gemini, batch_openai

    store = server.batches

    async def stats(request: web.Request) -> web.Response:
        return web.json_response(store.stats())

    async def clock(request: web.Request) -> web.Response:
        body = await request.json()
        store.offset += float(body.get("advance", 0.0))
        return web.json_response({"clock": store.now()})

    app.router.add_get("/batch/stats", stats)
    app.router.add_post("/batch/clock", clock)
    gemini = batch_gemini.add_routes(app, store)  # first: its /v1/files/{id}:download
    openai = batch_openai.add_routes(app, store)
    batch_anthropic.add_routes(app, store)

    def by_key(name: str) -> Handler:
        """Gemini's handler for a request with Google's API key, else OpenAI's."""

        async def route(request: web.Request) -> web.StreamResponse:
            google = "x-goog-api-key" in request.headers or "key" in request.query
            return await (gemini if google else openai)[name](request)

        return route

    app.router.add_get("/v1/batches", by_key("list"))
    app.router.add_get("/v1/batches/{batch_id}", by_key("retrieve"))
