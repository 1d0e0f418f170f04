"use strict";
// The participant's pages, in the order the study's design gives (the server's ParticipantFlow):
// consent, the instructions, the practice text, sorting pictures into groups (drag with a mouse, a
// finger or a pen; or select a picture and press "Move here", or a key), rating and describing each
// group, the attention and demographics questions, a pause between sets and the completion code.
// Every change is sent at once and the page shows what the server stored; a reload continues where
// it stopped.  No build step, no library.
const app = document.getElementById("app");
const noticeBox = document.getElementById("notice");
const KEY = "ramure-study-participant";
let me = null;          // {code, token}
let state = null;       // the server's state for this participant
let selected = null;    // label of the picture selected for a move
let pause = false;      // show the page between two parts
let justDragged = false;

function h(tag, attrs = {}, ...kids) {
  const el = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k.startsWith("on")) el.addEventListener(k.slice(2), v);
    else if (k === "dataset") Object.assign(el.dataset, v);
    else if (v === true) el.setAttribute(k, "");
    else if (v !== false && v !== null && v !== undefined) el.setAttribute(k, v);
  }
  for (const kid of kids.flat()) if (kid !== null && kid !== undefined) el.append(kid);
  return el;
}

function notice(text) { noticeBox.textContent = text; }

async function api(path, body) {
  const opts = {method: body ? "POST" : "GET", headers: {}};
  if (me) opts.headers.Authorization = "Bearer " + me.token;
  if (body) { opts.headers["Content-Type"] = "application/json"; opts.body = JSON.stringify(body); }
  const r = await fetch(path, opts);
  const data = await r.json().catch(() => ({error: r.statusText}));
  if (!r.ok) { const e = new Error(data.error || r.statusText); e.status = r.status; throw e; }
  return data;
}

function remembered() {
  const hash = location.hash.slice(1);
  const dot = hash.indexOf(".");
  if (dot > 0) return {code: hash.slice(0, dot), token: hash.slice(dot + 1)};
  try { return JSON.parse(localStorage.getItem(KEY) || "null"); } catch (e) { return null; }
}

async function start() {
  me = remembered();
  if (!me) return showConsent();
  try {
    state = await api(`/api/p/${encodeURIComponent(me.code)}/state`);
  } catch (e) {
    if (e.status === 403 || e.status === 404) { localStorage.removeItem(KEY); me = null; history.replaceState(null, "", "/"); return showConsent(); }
    return notice("The study cannot be reached: " + e.message);
  }
  localStorage.setItem(KEY, JSON.stringify(me));
  history.replaceState(null, "", location.pathname + location.search + "#" + me.code + "." + me.token);
  render();
}

async function showConsent() {
  const info = await api("/api/study");
  const agree = h("input", {type: "checkbox", id: "agree"});
  const go = h("button", {type: "button", id: "start", disabled: true}, "Start");
  agree.addEventListener("change", () => { go.disabled = !agree.checked; });
  go.addEventListener("click", async () => {
    go.disabled = true;
    const params = new URLSearchParams(location.search);
    const external = params.get("PROLIFIC_PID") || params.get("participant") || undefined;
    try {
      me = await api("/api/join", {consent: true, external_id: external});
      location.hash = me.code + "." + me.token;
      await start();
    } catch (e) { notice(e.message); go.disabled = false; }
  });
  app.replaceChildren(
    h("h1", {}, info.title),
    h("p", {class: "consent"}, info.consent),
    h("p", {}, agree, h("label", {for: "agree"}, " I have read this and agree to take part.")),
    h("p", {}, go),
  );
}

// -- sending answers ------------------------------------------------------------------------------
// Answers are sent one after the other, in the order given; each is built when its turn comes
// (a move from the stored grouping), and one made in a part that has ended since is dropped, so
// a double click on "Finish this part" never lands on the next part.
let queue = Promise.resolve();
let pending = 0;

function send(build) {
  const part = state.part;
  pending += 1;
  app.classList.add("busy");
  notice("Saving…");
  queue = queue.then(() => post(build, part)).finally(() => {
    pending -= 1;
    if (pending === 0) app.classList.remove("busy");
  });
}

async function post(build, part) {
  if (state.complete || state.part !== part) return;
  const body = typeof build === "function" ? build() : build;
  if (!body) return;
  try {
    state = await api(`/api/p/${encodeURIComponent(me.code)}/answer`, {...body, version: state.version, part});
    notice("Saved.");
    if (body.action === "finish" && !state.complete && !state.page) pause = true;
  } catch (e) {
    if (e.status === 409) {
      state = await api(`/api/p/${encodeURIComponent(me.code)}/state`);
      notice("This page was out of date and has been refreshed; please check your last change.");
    } else notice("Not saved: " + e.message);
  }
  if (selected && !(state.pictures || []).includes(selected)) selected = null;
  render();
}

function partition() { return state.groups.map(g => g.pictures.slice()); }

function moveTo(label, zone) {
  selected = null;
  send(() => {
    const groups = partition().map(g => g.filter(p => p !== label));
    if (zone === "new") groups.push([label]);
    else if (zone !== "pool") {
      const i = Number(zone) - 1;
      if (!(i >= 0 && i < groups.length)) return null;
      groups[i].push(label);
    }
    return {action: "groups", groups: groups.filter(g => g.length > 0)};
  });
}

// -- dragging with pointer events (mouse, touch, pen) -------------------------------------------------
let drag = null;

function zoneAt(x, y) {
  const el = document.elementFromPoint(x, y);
  return el ? el.closest("[data-zone]") : null;
}

function highlight(zone) {
  for (const z of document.querySelectorAll(".zone.over")) if (z !== zone) z.classList.remove("over");
  if (zone) zone.classList.add("over");
}

function pointerDown(ev) {
  if (ev.button !== 0) return;
  const el = ev.currentTarget;
  drag = {label: el.dataset.picture, el, x0: ev.clientX, y0: ev.clientY, moved: false, id: ev.pointerId};
}

document.addEventListener("pointermove", ev => {
  if (!drag || ev.pointerId !== drag.id) return;
  const dx = ev.clientX - drag.x0, dy = ev.clientY - drag.y0;
  if (!drag.moved && Math.hypot(dx, dy) < 6) return;
  drag.moved = true;
  drag.el.classList.add("dragging");
  drag.el.style.transform = `translate(${dx}px, ${dy}px)`;
  highlight(zoneAt(ev.clientX, ev.clientY));
  ev.preventDefault();
});

function endDrag(ev) {
  if (!drag || ev.pointerId !== drag.id) return;
  const d = drag;
  drag = null;
  d.el.style.transform = "";
  d.el.classList.remove("dragging");
  highlight(null);
  if (!d.moved || ev.type === "pointercancel") return;
  justDragged = true;
  setTimeout(() => { justDragged = false; }, 0);
  const zone = zoneAt(ev.clientX, ev.clientY);
  const from = d.el.closest("[data-zone]");
  if (zone && zone !== from) moveTo(d.label, zone.dataset.zone);
}
document.addEventListener("pointerup", endDrag);
document.addEventListener("pointercancel", endDrag);

// -- the pages ------------------------------------------------------------------------------------
function picture(label) {
  const img = h("img", {src: `/img/${encodeURIComponent(state.code)}/${state.part}/${encodeURIComponent(label)}?t=${encodeURIComponent(me.token)}`, alt: "picture " + label, draggable: "false"});
  return h("button", {
    type: "button", class: "pic", "aria-pressed": String(selected === label), dataset: {picture: label, key: "pic-" + label},
    title: "Drag to a group, or select and press Move here (keys: 1-9 a group, N a new group, 0 back)",
    onpointerdown: pointerDown,
    onclick: () => { if (justDragged) return; selected = selected === label ? null : label; render(); },
    onkeydown: ev => keyMove(ev, label),
  }, img, h("span", {}, label));
}

function keyMove(ev, label) {
  const k = ev.key.toLowerCase();
  if (k === "n") moveTo(label, "new");
  else if (k === "0" || k === "u") moveTo(label, "pool");
  else if (/^[1-9]$/.test(k) && Number(k) <= state.groups.length) moveTo(label, k);
  else return;
  ev.preventDefault();
}

function moveHere(zone) {
  if (!selected) return null;
  return h("button", {type: "button", class: "move", dataset: {key: "move-" + zone}, onclick: () => moveTo(selected, zone)}, "Move here");
}

function scale(group, name, question) {
  const legend = h("legend", {}, question);
  const boxes = state.levels.map((level, i) => h("label", {}, h("input", {
    type: "radio", name: `${name}-${group.label}`, value: String(i + 1), checked: group[name] === i + 1,
    dataset: {key: `${name}-${group.label}-${i + 1}`},
    onchange: () => send({action: "rate", group: group.label, [name]: i + 1}),
  }), " " + level));
  return h("fieldset", {class: "scale"}, legend, ...boxes);
}

function groupSection(group) {
  const several = group.pictures.length > 1;
  const parts = [
    h("h2", {}, `Group ${group.label}`, moveHere(String(group.label))),
    h("div", {class: "pics"}, group.pictures.map(picture)),
  ];
  if (several) {
    parts.push(h("fieldset", {class: "scale"}, h("legend", {}, "Which picture best stands for this group?"),
      ...group.pictures.map(label => h("label", {}, h("input", {
        type: "radio", name: `rep-${group.label}`, value: label, checked: group.representative === label,
        dataset: {key: `rep-${group.label}-${label}`},
        onchange: () => send({action: "representative", group: group.label, picture: label}),
      }), " " + label))));
  }
  parts.push(scale(group, "usefulness", state.questions.usefulness));
  parts.push(scale(group, "difference", state.questions.difference));
  if (several && group.representative) parts.push(scale(group, "representative_quality", state.questions.representative_quality));
  const word = h("input", {type: "text", maxlength: "80", placeholder: "a word or two", "aria-label": `words for group ${group.label}`, dataset: {key: `word-${group.label}`}});
  const add = () => { const text = word.value.trim(); word.value = ""; if (text) send({action: "add_word", group: group.label, text}); };
  word.addEventListener("keydown", ev => { if (ev.key === "Enter") { ev.preventDefault(); add(); } });
  parts.push(h("div", {class: "words"}, h("p", {}, "Describe this group in a few words:"),
    h("ul", {}, group.words.map(w => h("li", {}, w, " ", h("button", {type: "button", "aria-label": `remove ${w}`, onclick: () => send({action: "remove_word", group: group.label, text: w})}, "×")))),
    word, " ", h("button", {type: "button", dataset: {key: `add-${group.label}`}, onclick: add}, "Add")));
  return h("section", {class: "zone group", dataset: {zone: String(group.label)}}, ...parts);
}

function render() {
  // Keep what the participant is typing and where the focus is across the redraw.
  const focused = document.activeElement && document.activeElement.dataset ? document.activeElement.dataset.key : null;
  const typed = Array.from(app.querySelectorAll("input[type=text]")).map(i => [i.dataset.key, i.value]);
  if (state.complete) renderDone();
  else if (state.page) renderPage(state.page);
  else if (pause) renderPause();
  else renderTask();
  for (const [key, value] of typed) { const el = app.querySelector(`[data-key="${CSS.escape(key)}"]`); if (el) el.value = value; }
  if (focused) { const el = app.querySelector(`[data-key="${CSS.escape(focused)}"]`); if (el) el.focus(); }
}

function renderTask() {
  const pool = h("section", {class: "zone pool", dataset: {zone: "pool"}},
    h("h2", {}, "Pictures not in a group yet", moveHere("pool")),
    h("div", {class: "pics"}, state.unsorted.map(picture)));
  const fresh = h("section", {class: "zone new", dataset: {zone: "new"}},
    h("h2", {}, "New group", moveHere("new")), h("p", {}, "Drag a picture here to start a new group."));
  const todo = state.missing.length
    ? h("ul", {class: "missing"}, state.missing.map(m => h("li", {}, m)))
    : h("p", {}, "Everything is answered.");
  app.replaceChildren(
    h("p", {class: "progress"}, state.title),
    h("h1", {}, state.practice ? "Practice: sort the plants into groups" : "Sort the plants into groups"),
    h("p", {}, "Put plants that look alike in the same group. Then, for each group, choose the picture that best stands for it, answer the questions and describe it in a few words."),
    pool,
    h("div", {class: "groups"}, state.groups.map(groupSection), fresh),
    h("h2", {}, "Still to do"), todo,
    h("p", {}, h("button", {type: "button", id: "finish", disabled: state.missing.length > 0, onclick: () => send({action: "finish"})}, "Finish this part")),
  );
}

function renderPause() {
  app.replaceChildren(
    h("p", {class: "progress"}, state.part > 1 ? `Set ${state.part - 1} of ${state.parts} is done` : "Done"),
    h("h1", {}, "Saved. Take a short break if you like."),
    h("p", {}, `Next: ${state.title.toLowerCase()}, with other plants.`),
    h("p", {}, h("button", {type: "button", id: "continue", onclick: () => { pause = false; render(); }}, "Continue")),
  );
}

// A page of text (instructions, the practice) with Continue, or of questions (attention checks,
// demographics): every question answered by a choice, or by text where it offers none.
function renderPage(page) {
  const fields = page.questions.map(q => {
    if (!q.options.length) {
      return h("p", {}, h("label", {for: "q-" + q.key}, q.text + " "),
        h("input", {type: "text", id: "q-" + q.key, name: q.key, maxlength: "500", dataset: {key: "q-" + q.key}}));
    }
    return h("fieldset", {class: "scale"}, h("legend", {}, q.text), ...q.options.map((option, i) => h("label", {},
      h("input", {type: "radio", name: q.key, value: option, dataset: {key: `q-${q.key}-${i}`}}), " " + option)));
  });
  const go = h("button", {type: "button", id: "continue-page"}, "Continue");
  go.addEventListener("click", () => {
    if (!page.questions.length) return send({page: page.kind});
    const answers = {};
    for (const q of page.questions) {
      const chosen = app.querySelector(`input[name="${CSS.escape(q.key)}"]:checked`) || app.querySelector(`input[type=text][name="${CSS.escape(q.key)}"]`);
      if (chosen && chosen.value.trim()) answers[q.key] = chosen.value.trim();
    }
    send({page: page.kind, answers});
  });
  app.replaceChildren(
    h("h1", {}, page.title),
    ...page.text.split("\n\n").filter(t => t.trim()).map(t => h("p", {}, t)),
    ...fields,
    h("p", {}, go),
  );
}

function renderDone() {
  app.replaceChildren(
    h("h1", {}, "Thank you!"),
    h("p", {}, state.time_up ? "The time planned for this study is up; your answers so far are saved." : "All your answers are saved."),
    h("p", {}, "Your completion code:"),
    h("p", {}, h("output", {id: "completion", class: "code"}, state.completion_code)),
  );
}

start();
