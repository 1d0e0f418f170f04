-- Ramure user study on variant relevance (schema version 3: version 1, the events table since 2,
-- and since 3 settings, enrolments, page_answers and events.front_end).
-- Every statement is idempotent: running the whole file on a version-1 file migrates it.
-- Likert answers are stored as 1..4 (poor, fair, good, excellent).
CREATE TABLE IF NOT EXISTS study (
  id INTEGER PRIMARY KEY CHECK (id = 1),
  name TEXT NOT NULL,
  budget_seconds REAL NOT NULL CHECK (budget_seconds > 0),
  created_at TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS grammars (
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL UNIQUE,
  source TEXT                     -- exploration directory, or NULL for plain data
);
CREATE TABLE IF NOT EXISTS picks (
  grammar_id INTEGER NOT NULL REFERENCES grammars(id) ON DELETE CASCADE,
  pick_id INTEGER NOT NULL CHECK (pick_id BETWEEN 1 AND 27),
  variant_id INTEGER NOT NULL,
  pc1 REAL NOT NULL, pc2 REAL NOT NULL, pc3 REAL NOT NULL,
  params TEXT NOT NULL,           -- JSON {"rule": int, "constants": {...}}
  image TEXT,                     -- the picture, relative to the study folder when inside it
  PRIMARY KEY (grammar_id, pick_id)
);
CREATE TABLE IF NOT EXISTS participants (
  id INTEGER PRIMARY KEY,
  code TEXT NOT NULL UNIQUE,      -- anonymous code, e.g. P105
  seed INTEGER NOT NULL,          -- seeds the image order of each test
  consent INTEGER NOT NULL DEFAULT 0 CHECK (consent IN (0, 1)),
  consent_at TEXT,
  created_at TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS tests (
  id INTEGER PRIMARY KEY,
  participant_id INTEGER NOT NULL REFERENCES participants(id) ON DELETE CASCADE,
  grammar_id INTEGER NOT NULL REFERENCES grammars(id) ON DELETE CASCADE,
  started_at TEXT NOT NULL,
  finished_at TEXT,
  elapsed_seconds REAL NOT NULL DEFAULT 0,
  UNIQUE (participant_id, grammar_id)
);
CREATE TABLE IF NOT EXISTS groups (
  id INTEGER PRIMARY KEY,
  test_id INTEGER NOT NULL REFERENCES tests(id) ON DELETE CASCADE,
  label INTEGER NOT NULL,         -- 1.. in the participant's order
  representative INTEGER CHECK (representative BETWEEN 1 AND 27),
  usefulness INTEGER CHECK (usefulness BETWEEN 1 AND 4),
  difference INTEGER CHECK (difference BETWEEN 1 AND 4),
  representative_quality INTEGER CHECK (representative_quality BETWEEN 1 AND 4),
  UNIQUE (test_id, label)
);
CREATE TABLE IF NOT EXISTS group_images (
  group_id INTEGER NOT NULL REFERENCES groups(id) ON DELETE CASCADE,
  test_id INTEGER NOT NULL REFERENCES tests(id) ON DELETE CASCADE,
  pick_id INTEGER NOT NULL CHECK (pick_id BETWEEN 1 AND 27),
  PRIMARY KEY (group_id, pick_id),
  UNIQUE (test_id, pick_id)       -- an image is in at most one group per test
);
CREATE TABLE IF NOT EXISTS qualifiers (
  id INTEGER PRIMARY KEY,
  group_id INTEGER NOT NULL REFERENCES groups(id) ON DELETE CASCADE,
  text TEXT NOT NULL CHECK (length(trim(text)) > 0)
);
CREATE TABLE IF NOT EXISTS events (  -- every accepted action of a participant, in order
  id INTEGER PRIMARY KEY,
  participant_id INTEGER NOT NULL REFERENCES participants(id) ON DELETE CASCADE,
  test_id INTEGER REFERENCES tests(id) ON DELETE CASCADE,  -- NULL for consent
  at TEXT NOT NULL,               -- UTC ISO-8601, milliseconds
  elapsed_seconds REAL,           -- the test's time spent when it happened
  action TEXT NOT NULL,           -- consent, start, resume, group, representative, rate, ...
  detail TEXT NOT NULL DEFAULT '{}',  -- JSON: the answer, and any answer it dropped
  front_end TEXT                  -- desktop, notebook, web, simulated, script (NULL before version 3)
);
CREATE TABLE IF NOT EXISTS settings (  -- the study's design: key -> JSON (config, stimuli framing)
  key TEXT PRIMARY KEY,
  value TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS enrolments (  -- one per participant enrolled since version 3
  participant_id INTEGER PRIMARY KEY REFERENCES participants(id) ON DELETE CASCADE,
  external_id TEXT UNIQUE,        -- e.g. a Prolific PID, or NULL
  pilot INTEGER NOT NULL DEFAULT 0 CHECK (pilot IN (0, 1)),  -- trial runs, left out of the analysis
  grammar_order TEXT NOT NULL,    -- JSON list of grammar names (a Latin-square row)
  completion_code TEXT,
  withdrawn_at TEXT
);
CREATE TABLE IF NOT EXISTS page_answers (  -- instructions read, practice, attention checks, demographics
  participant_id INTEGER NOT NULL REFERENCES participants(id) ON DELETE CASCADE,
  page TEXT NOT NULL,
  answers TEXT NOT NULL,          -- JSON object
  at TEXT NOT NULL,
  PRIMARY KEY (participant_id, page)
);
CREATE INDEX IF NOT EXISTS tests_by_participant ON tests (participant_id);
CREATE INDEX IF NOT EXISTS groups_by_test ON groups (test_id);
CREATE INDEX IF NOT EXISTS qualifiers_by_group ON qualifiers (group_id);
