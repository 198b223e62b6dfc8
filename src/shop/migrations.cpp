// The hub's schema and functions, as versioned migrations (docs/shop.md).
// Each runs once, in order, in one transaction with the version row it adds;
// a shipped migration is never edited (a change is a new one).
#include "cncstream/shop/schema.hpp"

namespace cncstream::shop {

namespace {

// 1: tables, the three roles and the PC's functions.
constexpr const char* kMigration1 = R"SQL(
DO $$ BEGIN
  IF NOT EXISTS (SELECT 1 FROM pg_roles WHERE rolname = 'cncstream_pc') THEN CREATE ROLE cncstream_pc NOLOGIN; END IF;
  IF NOT EXISTS (SELECT 1 FROM pg_roles WHERE rolname = 'cncstream_operator') THEN CREATE ROLE cncstream_operator NOLOGIN; END IF;
  IF NOT EXISTS (SELECT 1 FROM pg_roles WHERE rolname = 'cncstream_reader') THEN CREATE ROLE cncstream_reader NOLOGIN; END IF;
END $$;

CREATE SCHEMA shop;
REVOKE ALL ON SCHEMA shop FROM PUBLIC;

CREATE TABLE shop.machines (
  id bigserial PRIMARY KEY,
  name text NOT NULL UNIQUE CHECK (name ~ '^[A-Za-z0-9_-]{1,32}$'),
  pc text NOT NULL DEFAULT '',
  profile text NOT NULL DEFAULT '',
  travel_mm double precision[],                 -- x, y, z
  capabilities text[] NOT NULL DEFAULT '{}',    -- free tags a job's needs must be among
  registered_at timestamptz NOT NULL DEFAULT now(),
  last_seen timestamptz
);

-- A row per machine, in MTConnect's words.
CREATE TABLE shop.machine_state (
  machine_id bigint PRIMARY KEY REFERENCES shop.machines(id),
  availability text NOT NULL DEFAULT 'UNAVAILABLE',
  execution text NOT NULL DEFAULT 'READY',
  controller_mode text NOT NULL DEFAULT 'MANUAL',
  program text NOT NULL DEFAULT '',
  line bigint NOT NULL DEFAULT 0,
  path_position double precision[],
  path_feedrate double precision,
  feed_override double precision,
  alarm text NOT NULL DEFAULT '',
  updated_at timestamptz NOT NULL DEFAULT now()
);

CREATE TABLE shop.jobs (
  id bigserial PRIMARY KEY,
  file_name text NOT NULL,
  kind text NOT NULL CHECK (kind IN ('stl', 'gcode')),
  content bytea NOT NULL,
  params jsonb,                                 -- an STL's tool path parameters (the daemon's API's)
  needs text[] NOT NULL DEFAULT '{}',           -- capabilities the machine must have
  machine text,                                 -- only this machine (NULL: any that can)
  status text NOT NULL DEFAULT 'pending' CHECK (status IN
    ('pending', 'assigned', 'awaiting_operator', 'running', 'completed', 'failed', 'interrupted', 'cancelled')),
  machine_id bigint REFERENCES shop.machines(id),
  lease_until timestamptz,
  last_line bigint NOT NULL DEFAULT 0,
  message text NOT NULL DEFAULT '',
  submitted_by text NOT NULL DEFAULT session_user,
  created_at timestamptz NOT NULL DEFAULT now(),
  claimed_at timestamptz,
  started_at timestamptz,
  ended_at timestamptz
);
CREATE INDEX jobs_pending ON shop.jobs (id) WHERE status = 'pending';
CREATE INDEX jobs_leased ON shop.jobs (lease_until) WHERE status IN ('assigned', 'awaiting_operator', 'running');

-- Every PC's journal events, once each: (machine, sequence) is the journal's own numbering.
CREATE TABLE shop.job_events (
  id bigserial PRIMARY KEY,
  machine_id bigint NOT NULL REFERENCES shop.machines(id),
  seq bigint NOT NULL,
  at timestamptz NOT NULL,
  kind text NOT NULL,
  job_id bigint REFERENCES shop.jobs(id),
  body jsonb NOT NULL DEFAULT '{}',
  received_at timestamptz NOT NULL DEFAULT now(),
  UNIQUE (machine_id, seq)
);
CREATE INDEX job_events_job ON shop.job_events (job_id, id);

-- A JSON array as an SQL array (NULL for anything else: null, missing).
CREATE FUNCTION shop.json_numbers(j jsonb) RETURNS double precision[] LANGUAGE sql IMMUTABLE AS $f$
  SELECT CASE WHEN jsonb_typeof(j) = 'array'
    THEN (SELECT array_agg(v::double precision) FROM jsonb_array_elements_text(j) v) END
$f$;
CREATE FUNCTION shop.json_texts(j jsonb) RETURNS text[] LANGUAGE sql IMMUTABLE AS $f$
  SELECT CASE WHEN jsonb_typeof(j) = 'array' THEN (SELECT array_agg(v) FROM jsonb_array_elements_text(j) v) END
$f$;

-- Leases that lapsed (a PC that stopped reporting): the job is interrupted
-- with its last reported line and never goes back to the queue by itself.
CREATE FUNCTION shop.expire_leases() RETURNS integer
LANGUAGE plpgsql SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
DECLARE n integer;
BEGIN
  UPDATE shop.jobs SET status = 'interrupted', ended_at = now(), lease_until = NULL,
    message = format('the lease lapsed at %s while %s (the PC stopped reporting); last reported line %s; '
                     'not restarted: an operator requeues it', to_char(now(), 'YYYY-MM-DD HH24:MI:SS'),
                     replace(status, '_', ' '), last_line)
  WHERE status IN ('assigned', 'awaiting_operator', 'running') AND lease_until < now();
  GET DIAGNOSTICS n = ROW_COUNT;
  RETURN n;
END $f$;

-- A PC's machine says it is alive: registers it (or updates what it is),
-- stores its state, renews the leases of its jobs and sweeps lapsed ones.
CREATE FUNCTION shop.heartbeat(p_machine text, p_pc text, p_info jsonb, p_state jsonb, p_lease_s double precision)
RETURNS jsonb LANGUAGE plpgsql SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
DECLARE mid bigint; jobs jsonb;
BEGIN
  IF p_lease_s IS NULL OR p_lease_s <= 0 OR p_lease_s > 86400 THEN
    RAISE EXCEPTION 'heartbeat: lease_s % is out of range (0, 86400]', p_lease_s;
  END IF;
  INSERT INTO shop.machines AS m (name, pc, profile, travel_mm, capabilities, last_seen)
  VALUES (p_machine, coalesce(p_pc, ''), coalesce(p_info->>'profile', ''),
          shop.json_numbers(p_info->'travel_mm'),
          coalesce(shop.json_texts(p_info->'capabilities'), '{}'), now())
  ON CONFLICT (name) DO UPDATE SET pc = excluded.pc, profile = excluded.profile, travel_mm = excluded.travel_mm,
    capabilities = excluded.capabilities, last_seen = now()
  RETURNING id INTO mid;
  INSERT INTO shop.machine_state AS s (machine_id, availability, execution, controller_mode, program, line,
                                       path_position, path_feedrate, feed_override, alarm, updated_at)
  VALUES (mid, coalesce(p_state->>'availability', 'UNAVAILABLE'), coalesce(p_state->>'execution', 'READY'),
          coalesce(p_state->>'controller_mode', 'MANUAL'), coalesce(p_state->>'program', ''),
          coalesce((p_state->>'line')::bigint, 0),
          shop.json_numbers(p_state->'path_position'),
          (p_state->>'path_feedrate')::double precision, (p_state->>'feed_override')::double precision,
          coalesce(p_state->>'alarm', ''), now())
  ON CONFLICT (machine_id) DO UPDATE SET availability = excluded.availability, execution = excluded.execution,
    controller_mode = excluded.controller_mode, program = excluded.program, line = excluded.line,
    path_position = excluded.path_position, path_feedrate = excluded.path_feedrate,
    feed_override = excluded.feed_override, alarm = excluded.alarm, updated_at = now();
  UPDATE shop.jobs SET lease_until = now() + make_interval(secs => p_lease_s)
  WHERE machine_id = mid AND status IN ('assigned', 'awaiting_operator', 'running');
  PERFORM shop.expire_leases();
  SELECT coalesce(jsonb_agg(jsonb_build_object('id', id, 'status', status) ORDER BY id), '[]') INTO jobs
  FROM shop.jobs WHERE machine_id = mid AND status IN ('assigned', 'awaiting_operator', 'running', 'cancelled')
    AND (ended_at IS NULL OR ended_at > now() - interval '1 hour');
  RETURN jsonb_build_object('machine_id', mid, 'jobs', jobs);
END $f$;

-- The oldest pending job this machine can do, claimed once however many ask
-- at the same moment (SKIP LOCKED). It then waits for the operator there.
CREATE FUNCTION shop.claim_job(p_machine text, p_lease_s double precision)
RETURNS TABLE (id bigint, file_name text, kind text, content bytea, params jsonb)
LANGUAGE plpgsql SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
DECLARE m shop.machines;
BEGIN
  IF p_lease_s IS NULL OR p_lease_s <= 0 OR p_lease_s > 86400 THEN
    RAISE EXCEPTION 'claim_job: lease_s % is out of range (0, 86400]', p_lease_s;
  END IF;
  SELECT * INTO m FROM shop.machines WHERE name = p_machine;
  IF NOT FOUND THEN
    RAISE EXCEPTION 'claim_job: no machine named % (a heartbeat registers it)', p_machine;
  END IF;
  PERFORM shop.expire_leases();
  RETURN QUERY
  UPDATE shop.jobs j SET status = 'assigned', machine_id = m.id, claimed_at = now(),
    lease_until = now() + make_interval(secs => p_lease_s), message = ''
  WHERE j.id = (SELECT c.id FROM shop.jobs c
                WHERE c.status = 'pending' AND (c.machine IS NULL OR c.machine = m.name)
                  AND c.needs <@ m.capabilities
                ORDER BY c.id FOR UPDATE SKIP LOCKED LIMIT 1)
  RETURNING j.id, j.file_name, j.kind, j.content, j.params;
END $f$;

-- What one event does to the job and the machine's state (only the first
-- time it arrives: report_events calls it for rows it inserted).
CREATE FUNCTION shop.apply_event(p_machine_id bigint, p_job bigint, p_kind text, p_body jsonb)
RETURNS void LANGUAGE plpgsql SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
DECLARE local_state text; st text; v_line bigint;
BEGIN
  IF p_kind = 'job' AND p_job IS NOT NULL THEN
    local_state := p_body->>'state';
    v_line := coalesce((p_body->>'last_line')::bigint, 0);
    st := CASE local_state
      WHEN 'ready' THEN 'awaiting_operator' WHEN 'running' THEN 'running' WHEN 'held' THEN 'running'
      WHEN 'done' THEN 'completed' WHEN 'failed' THEN 'failed' WHEN 'interrupted' THEN 'interrupted'
      WHEN 'stopped' THEN 'cancelled' WHEN 'cancelled' THEN 'cancelled' ELSE NULL END;
    IF st IS NULL THEN
      RETURN;  -- queued, generating: still assigned
    END IF;
    -- A job the machine runs, or one whose lease lapsed while it ran on this
    -- machine (the truth arriving late); never one requeued elsewhere.
    UPDATE shop.jobs SET
      status = CASE WHEN st = 'awaiting_operator' AND status <> 'assigned' THEN status ELSE st END,
      last_line = greatest(last_line, v_line),
      message = coalesce(p_body->>'message', message),
      started_at = CASE WHEN st = 'running' THEN coalesce(started_at, now()) ELSE started_at END,
      ended_at = CASE WHEN st IN ('completed', 'failed', 'interrupted', 'cancelled') THEN now() ELSE NULL END,
      lease_until = CASE WHEN st IN ('completed', 'failed', 'interrupted', 'cancelled') THEN NULL ELSE lease_until END
    WHERE id = p_job AND machine_id = p_machine_id
      AND (status IN ('assigned', 'awaiting_operator', 'running') OR (status = 'interrupted' AND ended_at IS NOT NULL
           AND st IN ('completed', 'failed', 'interrupted', 'cancelled')));
  ELSIF p_kind = 'progress' AND p_job IS NOT NULL THEN
    UPDATE shop.jobs SET last_line = greatest(last_line, coalesce((p_body->>'line')::bigint, 0))
    WHERE id = p_job AND machine_id = p_machine_id;
  ELSIF p_kind = 'state' THEN
    UPDATE shop.machine_state SET
      availability = coalesce(p_body->>'availability', availability),
      execution = coalesce(p_body->>'execution', execution),
      controller_mode = coalesce(p_body->>'controller_mode', controller_mode),
      program = coalesce(p_body->>'program', program),
      line = coalesce((p_body->>'line')::bigint, line),
      alarm = coalesce(p_body->>'alarm', alarm), updated_at = now()
    WHERE machine_id = p_machine_id;
  END IF;
END $f$;

-- A PC ships its journal's events: stored once each (replays are ignored),
-- in order; returns the highest sequence now stored for the machine.
CREATE FUNCTION shop.report_events(p_machine text, p_events jsonb)
RETURNS bigint LANGUAGE plpgsql SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
DECLARE mid bigint; e record; inserted bigint; job bigint;
BEGIN
  SELECT m.id INTO mid FROM shop.machines m WHERE m.name = p_machine;
  IF NOT FOUND THEN
    RAISE EXCEPTION 'report_events: no machine named % (a heartbeat registers it)', p_machine;
  END IF;
  FOR e IN SELECT * FROM jsonb_to_recordset(p_events) AS x(seq bigint, at timestamptz, kind text, job bigint, body jsonb)
           ORDER BY x.seq LOOP
    IF e.seq IS NULL OR e.kind IS NULL THEN
      RAISE EXCEPTION 'report_events: an event without seq or kind';
    END IF;
    -- Only a job of this machine is linked (a wrong id must not block the outbox).
    SELECT j.id INTO job FROM shop.jobs j WHERE j.id = e.job AND j.machine_id = mid;
    inserted := NULL;
    INSERT INTO shop.job_events (machine_id, seq, at, kind, job_id, body)
    VALUES (mid, e.seq, coalesce(e.at, now()), e.kind, job, coalesce(e.body, '{}'))
    ON CONFLICT (machine_id, seq) DO NOTHING RETURNING job_events.id INTO inserted;
    IF inserted IS NOT NULL THEN
      PERFORM shop.apply_event(mid, job, e.kind, coalesce(e.body, '{}'));
    END IF;
  END LOOP;
  RETURN (SELECT coalesce(max(seq), 0) FROM shop.job_events WHERE machine_id = mid);
END $f$;

-- The operator's side: submitting, cancelling and requeueing jobs.
CREATE FUNCTION shop.submit_job(p_file_name text, p_kind text, p_content bytea, p_params jsonb, p_needs text[],
                                p_machine text)
RETURNS bigint LANGUAGE plpgsql SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
DECLARE jid bigint;
BEGIN
  IF p_machine IS NOT NULL AND NOT EXISTS (SELECT 1 FROM shop.machines WHERE name = p_machine) THEN
    RAISE EXCEPTION 'submit_job: no machine named % has joined the shop', p_machine;
  END IF;
  INSERT INTO shop.jobs (file_name, kind, content, params, needs, machine, submitted_by)
  VALUES (p_file_name, p_kind, p_content, p_params, coalesce(p_needs, '{}'), p_machine, session_user)
  RETURNING id INTO jid;
  PERFORM pg_notify('cncstream_jobs', jid::text);  -- a wake-up for claimers; they read the table
  RETURN jid;
END $f$;

CREATE FUNCTION shop.cancel_job(p_job bigint) RETURNS text
LANGUAGE plpgsql SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
DECLARE st text;
BEGIN
  UPDATE shop.jobs SET status = 'cancelled', ended_at = now(), lease_until = NULL,
    message = 'cancelled by ' || session_user
  WHERE id = p_job AND status IN ('pending', 'assigned', 'awaiting_operator') RETURNING status INTO st;
  IF NOT FOUND THEN
    SELECT status INTO st FROM shop.jobs WHERE id = p_job;
    RAISE EXCEPTION 'cancel_job: job % is %; only a job that has not started is cancelled here', p_job, coalesce(st, 'unknown');
  END IF;
  RETURN st;
END $f$;

-- An interrupted or failed job back in the queue: on the same machine
-- (p_same_machine, to resume there) or on any that can do it.
CREATE FUNCTION shop.requeue_job(p_job bigint, p_same_machine boolean) RETURNS void
LANGUAGE plpgsql SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
BEGIN
  UPDATE shop.jobs j SET status = 'pending', lease_until = NULL, ended_at = NULL, claimed_at = NULL,
    machine = CASE WHEN p_same_machine THEN (SELECT m.name FROM shop.machines m WHERE m.id = j.machine_id) ELSE j.machine END,
    machine_id = NULL, message = 'requeued by ' || session_user || ' after: ' || j.message
  WHERE j.id = p_job AND j.status IN ('interrupted', 'failed', 'cancelled');
  IF NOT FOUND THEN
    RAISE EXCEPTION 'requeue_job: job % is not interrupted, failed or cancelled', p_job;
  END IF;
  PERFORM pg_notify('cncstream_jobs', p_job::text);
END $f$;

REVOKE ALL ON ALL TABLES IN SCHEMA shop FROM PUBLIC;
REVOKE ALL ON ALL FUNCTIONS IN SCHEMA shop FROM PUBLIC;
GRANT USAGE ON SCHEMA shop TO cncstream_pc, cncstream_operator, cncstream_reader;
GRANT EXECUTE ON FUNCTION shop.claim_job(text, double precision), shop.report_events(text, jsonb),
  shop.heartbeat(text, text, jsonb, jsonb, double precision) TO cncstream_pc;
GRANT EXECUTE ON FUNCTION shop.submit_job(text, text, bytea, jsonb, text[], text), shop.cancel_job(bigint),
  shop.requeue_job(bigint, boolean) TO cncstream_operator;
GRANT SELECT ON ALL TABLES IN SCHEMA shop TO cncstream_reader, cncstream_operator;
)SQL";

// 2: the shop view's reads (docs/shop.md): every machine with its state, the
// queue and history with filters, a job's events. Read-only and SECURITY
// DEFINER, so a PC's login (which reads no table) can serve the view from
// any daemon; a job's file (content) is never returned.
constexpr const char* kMigration2 = R"SQL(
CREATE FUNCTION shop.view_machines() RETURNS jsonb
LANGUAGE sql STABLE SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
  SELECT jsonb_build_object('now', now(), 'machines', coalesce(jsonb_agg(jsonb_build_object(
    'name', m.name, 'pc', m.pc, 'profile', m.profile, 'travel_mm', to_jsonb(m.travel_mm),
    'capabilities', to_jsonb(m.capabilities), 'registered_at', m.registered_at, 'last_seen', m.last_seen,
    'heartbeat_age_s', round(extract(epoch FROM now() - m.last_seen)::numeric, 3),
    'state', CASE WHEN s.machine_id IS NULL THEN NULL ELSE jsonb_build_object(
      'availability', s.availability, 'execution', s.execution, 'controller_mode', s.controller_mode,
      'program', s.program, 'line', s.line, 'path_position', to_jsonb(s.path_position),
      'path_feedrate', s.path_feedrate, 'feed_override', s.feed_override, 'alarm', s.alarm,
      'updated_at', s.updated_at) END,
    'job', (SELECT jsonb_build_object('id', j.id, 'file_name', j.file_name, 'status', j.status, 'last_line', j.last_line)
            FROM shop.jobs j WHERE j.machine_id = m.id AND j.status IN ('assigned', 'awaiting_operator', 'running')
            ORDER BY j.id DESC LIMIT 1)
  ) ORDER BY m.pc, m.name), '[]'::jsonb))
  FROM shop.machines m LEFT JOIN shop.machine_state s ON s.machine_id = m.id
$f$;

CREATE FUNCTION shop.job_json(j shop.jobs) RETURNS jsonb
LANGUAGE sql STABLE SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
  SELECT jsonb_build_object('id', j.id, 'file_name', j.file_name, 'kind', j.kind, 'bytes', octet_length(j.content),
    'params', j.params, 'needs', to_jsonb(j.needs), 'requested_machine', j.machine,
    'machine', (SELECT m.name FROM shop.machines m WHERE m.id = j.machine_id), 'status', j.status,
    'last_line', j.last_line, 'message', j.message, 'submitted_by', j.submitted_by, 'created_at', j.created_at,
    'claimed_at', j.claimed_at, 'started_at', j.started_at, 'ended_at', j.ended_at, 'lease_until', j.lease_until)
$f$;

-- Newest first. p_statuses NULL: any; p_machine: the machine it went to or
-- the one it asks for; p_before: ids below it (the next page).
CREATE FUNCTION shop.view_jobs(p_statuses text[], p_machine text, p_limit integer, p_before bigint) RETURNS jsonb
LANGUAGE sql STABLE SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
  WITH f AS (
    SELECT j.id, j.status FROM shop.jobs j
    WHERE (p_statuses IS NULL OR j.status = ANY (p_statuses))
      AND (p_machine IS NULL OR j.machine = p_machine
           OR j.machine_id = (SELECT m.id FROM shop.machines m WHERE m.name = p_machine))
  ), page AS (
    SELECT f.id FROM f WHERE p_before IS NULL OR f.id < p_before
    ORDER BY f.id DESC LIMIT greatest(1, least(coalesce(p_limit, 100), 500))
  )
  SELECT jsonb_build_object('now', now(),
    'jobs', coalesce((SELECT jsonb_agg(shop.job_json(j) ORDER BY j.id DESC)
                      FROM shop.jobs j JOIN page ON page.id = j.id), '[]'::jsonb),
    'counts', coalesce((SELECT jsonb_object_agg(c.status, c.n) FROM
                          (SELECT f.status, count(*) AS n FROM f GROUP BY f.status) c), '{}'::jsonb))
$f$;

-- NULL when there is no such job.
CREATE FUNCTION shop.view_job_events(p_job bigint, p_limit integer) RETURNS jsonb
LANGUAGE sql STABLE SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
  SELECT jsonb_build_object('job', shop.job_json(j),
    'events', coalesce((SELECT jsonb_agg(jsonb_build_object('machine', m.name, 'seq', e.seq, 'at', e.at,
                                          'kind', e.kind, 'body', e.body, 'received_at', e.received_at) ORDER BY e.id)
                        FROM (SELECT * FROM shop.job_events WHERE job_id = j.id ORDER BY id
                              LIMIT greatest(1, least(coalesce(p_limit, 1000), 5000))) e
                        JOIN shop.machines m ON m.id = e.machine_id), '[]'::jsonb))
  FROM shop.jobs j WHERE j.id = p_job
$f$;

REVOKE ALL ON FUNCTION shop.view_machines(), shop.job_json(shop.jobs),
  shop.view_jobs(text[], text, integer, bigint), shop.view_job_events(bigint, integer) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION shop.view_machines(), shop.view_jobs(text[], text, integer, bigint),
  shop.view_job_events(bigint, integer) TO cncstream_pc, cncstream_operator, cncstream_reader;
)SQL";

// 3: the hub says when the shop view changed (docs/shop.md, "The shop view"):
// a NOTIFY on channel cncstream_state, payload "machine:NAME" or "job:ID",
// after any change to a machine's state or a job, whichever function (or an
// administrator's UPDATE) made it; sent at commit, identical ones in one
// transaction once. A wake-up only: the daemons that LISTEN re-read the view.
// Triggers rather than new copies of migration 1's functions: nothing that
// writes these tables can forget to notify.
constexpr const char* kMigration3 = R"SQL(
CREATE FUNCTION shop.notify_machine_state() RETURNS trigger
LANGUAGE plpgsql SET search_path = shop, pg_temp AS $f$
BEGIN
  PERFORM pg_notify('cncstream_state', 'machine:' || (SELECT m.name FROM shop.machines m WHERE m.id = NEW.machine_id));
  RETURN NULL;
END $f$;

CREATE FUNCTION shop.notify_job() RETURNS trigger
LANGUAGE plpgsql SET search_path = shop, pg_temp AS $f$
BEGIN
  PERFORM pg_notify('cncstream_state', 'job:' || NEW.id);
  RETURN NULL;
END $f$;

-- What the view shows of a machine's state (not its position or feed, which
-- every heartbeat of a moving machine changes).
CREATE TRIGGER machine_state_inserted AFTER INSERT ON shop.machine_state
  FOR EACH ROW EXECUTE FUNCTION shop.notify_machine_state();
CREATE TRIGGER machine_state_changed AFTER UPDATE ON shop.machine_state
  FOR EACH ROW WHEN ((OLD.availability, OLD.execution, OLD.controller_mode, OLD.program, OLD.line, OLD.alarm)
                     IS DISTINCT FROM (NEW.availability, NEW.execution, NEW.controller_mode, NEW.program, NEW.line,
                                       NEW.alarm))
  EXECUTE FUNCTION shop.notify_machine_state();
CREATE TRIGGER job_inserted AFTER INSERT ON shop.jobs
  FOR EACH ROW EXECUTE FUNCTION shop.notify_job();
CREATE TRIGGER job_changed AFTER UPDATE ON shop.jobs
  FOR EACH ROW WHEN ((OLD.status, OLD.machine_id, OLD.machine, OLD.last_line, OLD.message)
                     IS DISTINCT FROM (NEW.status, NEW.machine_id, NEW.machine, NEW.last_line, NEW.message))
  EXECUTE FUNCTION shop.notify_job();

REVOKE ALL ON FUNCTION shop.notify_machine_state(), shop.notify_job() FROM PUBLIC;
)SQL";

// 4: a daemon's web page submits, cancels and requeues (issue 29: "the same
// from any daemon's web page"). A daemon logs in with its PC's login
// (cncstream_pc, which may only claim, report and heartbeat), so the three
// operator functions get a role of their own that holds nothing else: a shop
// grants it to the PCs whose pages may act (docs/shop.md, "Roles"). The
// functions record the PC's login as who submitted or cancelled.
constexpr const char* kMigration4 = R"SQL(
DO $$ BEGIN
  IF NOT EXISTS (SELECT 1 FROM pg_roles WHERE rolname = 'cncstream_web_operator') THEN
    CREATE ROLE cncstream_web_operator NOLOGIN;
  END IF;
END $$;
GRANT USAGE ON SCHEMA shop TO cncstream_web_operator;
GRANT EXECUTE ON FUNCTION shop.submit_job(text, text, bytea, jsonb, text[], text), shop.cancel_job(bigint),
  shop.requeue_job(bigint, boolean) TO cncstream_web_operator;
)SQL";


// 5: resume on the same machine, and the live view's changed rows
// (docs/shop.md). A job requeued on the machine it ran on carries the line
// to resume after (its last reported line, what that machine's journal
// shipped): only that machine claims it, and its daemon queues it as a
// resume from that line (the same planning as `cncstream resume`), waiting
// for the operator like every claimed job. Requeued anywhere, it is a
// restart from the top. claim_job returns the line (a new column: the
// function is made again with the same name, arguments and grant, so a PC's
// role still holds exactly its three functions). view_changes reads only the
// machines and jobs a wake-up named, as view_machines and view_jobs show
// them, so a daemon pushes what changed rather than the whole view.
constexpr const char* kMigration5 = R"SQL(
-- Set by a requeue on the machine it ran on: only that machine claims it
-- (the submitter's own `machine` stays as asked), after that line (NULL: from the top).
ALTER TABLE shop.jobs ADD COLUMN resume_machine_id bigint REFERENCES shop.machines(id),
  ADD COLUMN resume_after_line bigint CHECK (resume_after_line IS NULL OR resume_after_line > 0);

CREATE OR REPLACE FUNCTION shop.requeue_job(p_job bigint, p_same_machine boolean) RETURNS void
LANGUAGE plpgsql SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
DECLARE j shop.jobs; ran_on text;
BEGIN
  SELECT * INTO j FROM shop.jobs WHERE id = p_job FOR UPDATE;
  IF NOT FOUND OR j.status NOT IN ('interrupted', 'failed', 'cancelled') THEN
    RAISE EXCEPTION 'requeue_job: job % is not interrupted, failed or cancelled', p_job;
  END IF;
  SELECT m.name INTO ran_on FROM shop.machines m WHERE m.id = j.machine_id;
  IF p_same_machine AND ran_on IS NULL THEN
    RAISE EXCEPTION 'requeue_job: job % never reached a machine; requeue it on any machine', p_job;
  END IF;
  UPDATE shop.jobs SET status = 'pending', lease_until = NULL, ended_at = NULL, claimed_at = NULL, started_at = NULL,
    resume_machine_id = CASE WHEN p_same_machine THEN j.machine_id END,
    resume_after_line = CASE WHEN p_same_machine AND j.last_line > 0 THEN j.last_line END,
    last_line = CASE WHEN p_same_machine THEN j.last_line ELSE 0 END,
    machine_id = NULL,
    message = CASE WHEN p_same_machine AND j.last_line > 0
                   THEN format('requeued by %s on %s, to resume after line %s; after: %s', session_user, ran_on,
                               j.last_line, j.message)
                   WHEN p_same_machine
                   THEN format('requeued by %s on %s (no line was reported: from the top); after: %s', session_user,
                               ran_on, j.message)
                   ELSE format('requeued by %s on any machine, from the top; after: %s', session_user, j.message) END
  WHERE id = p_job;
  PERFORM pg_notify('cncstream_jobs', p_job::text);
END $f$;

DROP FUNCTION shop.claim_job(text, double precision);
CREATE FUNCTION shop.claim_job(p_machine text, p_lease_s double precision)
RETURNS TABLE (id bigint, file_name text, kind text, content bytea, params jsonb, resume_after_line bigint)
LANGUAGE plpgsql SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
DECLARE m shop.machines;
BEGIN
  IF p_lease_s IS NULL OR p_lease_s <= 0 OR p_lease_s > 86400 THEN
    RAISE EXCEPTION 'claim_job: lease_s % is out of range (0, 86400]', p_lease_s;
  END IF;
  SELECT * INTO m FROM shop.machines WHERE name = p_machine;
  IF NOT FOUND THEN
    RAISE EXCEPTION 'claim_job: no machine named % (a heartbeat registers it)', p_machine;
  END IF;
  PERFORM shop.expire_leases();
  RETURN QUERY
  UPDATE shop.jobs j SET status = 'assigned', machine_id = m.id, claimed_at = now(),
    lease_until = now() + make_interval(secs => p_lease_s), message = ''
  WHERE j.id = (SELECT c.id FROM shop.jobs c
                WHERE c.status = 'pending' AND (c.machine IS NULL OR c.machine = m.name)
                  AND (c.resume_machine_id IS NULL OR c.resume_machine_id = m.id)
                  AND c.needs <@ m.capabilities
                ORDER BY c.id FOR UPDATE SKIP LOCKED LIMIT 1)
  RETURNING j.id, j.file_name, j.kind, j.content, j.params, j.resume_after_line;
END $f$;
REVOKE ALL ON FUNCTION shop.claim_job(text, double precision) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION shop.claim_job(text, double precision) TO cncstream_pc;

CREATE OR REPLACE FUNCTION shop.job_json(j shop.jobs) RETURNS jsonb
LANGUAGE sql STABLE SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
  SELECT jsonb_build_object('id', j.id, 'file_name', j.file_name, 'kind', j.kind, 'bytes', octet_length(j.content),
    'params', j.params, 'needs', to_jsonb(j.needs), 'requested_machine', j.machine,
    'machine', (SELECT m.name FROM shop.machines m WHERE m.id = j.machine_id), 'status', j.status,
    'last_line', j.last_line, 'resume_after_line', j.resume_after_line,
    'resume_machine', (SELECT m.name FROM shop.machines m WHERE m.id = j.resume_machine_id), 'message', j.message,
    'submitted_by', j.submitted_by, 'created_at', j.created_at, 'claimed_at', j.claimed_at,
    'started_at', j.started_at, 'ended_at', j.ended_at, 'lease_until', j.lease_until)
$f$;

-- One machine as the view shows it (view_machines' row).
CREATE FUNCTION shop.machine_json(m shop.machines) RETURNS jsonb
LANGUAGE sql STABLE SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
  SELECT jsonb_build_object(
    'name', m.name, 'pc', m.pc, 'profile', m.profile, 'travel_mm', to_jsonb(m.travel_mm),
    'capabilities', to_jsonb(m.capabilities), 'registered_at', m.registered_at, 'last_seen', m.last_seen,
    'heartbeat_age_s', round(extract(epoch FROM now() - m.last_seen)::numeric, 3),
    'state', (SELECT jsonb_build_object(
      'availability', s.availability, 'execution', s.execution, 'controller_mode', s.controller_mode,
      'program', s.program, 'line', s.line, 'path_position', to_jsonb(s.path_position),
      'path_feedrate', s.path_feedrate, 'feed_override', s.feed_override, 'alarm', s.alarm,
      'updated_at', s.updated_at) FROM shop.machine_state s WHERE s.machine_id = m.id),
    'job', (SELECT jsonb_build_object('id', j.id, 'file_name', j.file_name, 'status', j.status, 'last_line', j.last_line)
            FROM shop.jobs j WHERE j.machine_id = m.id AND j.status IN ('assigned', 'awaiting_operator', 'running')
            ORDER BY j.id DESC LIMIT 1))
$f$;

CREATE OR REPLACE FUNCTION shop.view_machines() RETURNS jsonb
LANGUAGE sql STABLE SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
  SELECT jsonb_build_object('now', now(),
    'machines', coalesce(jsonb_agg(shop.machine_json(m) ORDER BY m.pc, m.name), '[]'::jsonb))
  FROM shop.machines m
$f$;

-- The machines and jobs named (a wake-up's payloads), as the view shows
-- them, with the machine each job is on (its row shows the job); a name or
-- id that is not (any more) is left out.
CREATE FUNCTION shop.view_changes(p_machines text[], p_jobs bigint[]) RETURNS jsonb
LANGUAGE sql STABLE SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
  SELECT jsonb_build_object('now', now(),
    'machines', coalesce((SELECT jsonb_agg(shop.machine_json(m) ORDER BY m.pc, m.name) FROM shop.machines m
                          WHERE m.name = ANY (coalesce(p_machines, '{}'))
                             OR m.id IN (SELECT j.machine_id FROM shop.jobs j WHERE j.id = ANY (coalesce(p_jobs, '{}')))),
                         '[]'::jsonb),
    'jobs', coalesce((SELECT jsonb_agg(shop.job_json(j) ORDER BY j.id DESC) FROM shop.jobs j
                      WHERE j.id = ANY (coalesce(p_jobs, '{}'))), '[]'::jsonb))
$f$;

-- A claim whose answer never reached its PC (the hub fell silent after it
-- committed, the PC gave up waiting): the PC, finding at a heartbeat a job
-- assigned to its machine that it never received, reports it "released"
-- through its outbox, and the job goes back to the queue as it was. Only
-- an assigned job (never a program loaded, never a line cut). The earlier
-- apply_event does the rest, unchanged.
ALTER FUNCTION shop.apply_event(bigint, bigint, text, jsonb) RENAME TO apply_event_4;
CREATE FUNCTION shop.apply_event(p_machine_id bigint, p_job bigint, p_kind text, p_body jsonb)
RETURNS void LANGUAGE plpgsql SECURITY DEFINER SET search_path = shop, pg_temp AS $f$
BEGIN
  IF p_kind = 'job' AND p_job IS NOT NULL AND p_body->>'state' = 'released' THEN
    UPDATE shop.jobs SET status = 'pending', machine_id = NULL, claimed_at = NULL, lease_until = NULL,
      message = coalesce(p_body->>'message', 'its claim never reached the machine; back in the queue')
    WHERE id = p_job AND machine_id = p_machine_id AND status = 'assigned';
    RETURN;
  END IF;
  PERFORM shop.apply_event_4(p_machine_id, p_job, p_kind, p_body);
END $f$;

REVOKE ALL ON FUNCTION shop.apply_event(bigint, bigint, text, jsonb) FROM PUBLIC;
REVOKE ALL ON FUNCTION shop.machine_json(shop.machines), shop.view_changes(text[], bigint[]) FROM PUBLIC;
GRANT EXECUTE ON FUNCTION shop.view_changes(text[], bigint[]) TO cncstream_pc, cncstream_operator, cncstream_reader;
)SQL";

}  // namespace

const std::vector<Migration>& migrations() {
  static const std::vector<Migration> all = {
      {1, "tables, roles, claim_job, report_events, heartbeat, submit/cancel/requeue", kMigration1},
      {2, "the shop view's reads: view_machines, view_jobs, view_job_events", kMigration2},
      {3, "NOTIFY cncstream_state when a machine's state or a job changes", kMigration3},
      {4, "cncstream_web_operator: a daemon's web page submits, cancels and requeues", kMigration4},
      {5, "requeue on the same machine resumes after the last reported line; view_changes", kMigration5},
  };
  return all;
}

}  // namespace cncstream::shop
