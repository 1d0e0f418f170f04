"use strict";
// A Ramure study as a jsPsych 8 experiment (written by `ramure study export-jspsych`).
// Two plugins, no other library: RamureConsent (the consent page) and RamurePart (one stimulus
// set: sort the pictures into groups, then choose a representative, answer the questions and
// give words for each group).  Everything is done with buttons, so a keyboard (Tab, Space,
// Enter) or a finger works as well as a mouse.  The data of each part (one jsPsych trial) is what
// `ramure study import-jspsych` reads: picture codes, never pick numbers (they encode the PCA
// lattice), the labels and order this participant saw, the groups and their answers.
// On JATOS the data is submitted with jatos.js; elsewhere it is offered as a download.

(function () {
  const TASK = window.RAMURE_TASK;
  const LETTERS = "ABCDEFGHJKLMNPQRSTUVWXYZ", DIGITS = "23456789";

  function h(tag, attrs, ...kids) {
    const el = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (k.startsWith("on")) el.addEventListener(k.slice(2), v);
      else if (v === true) el.setAttribute(k, "");
      else if (v !== false && v !== null && v !== undefined) el.setAttribute(k, v);
    }
    for (const kid of kids.flat()) if (kid !== null && kid !== undefined) el.append(kid);
    return el;
  }

  function shuffled(items) {
    const out = items.slice();
    for (let i = out.length - 1; i > 0; i--) {
      const j = Math.floor(Math.random() * (i + 1));
      [out[i], out[j]] = [out[j], out[i]];
    }
    return out;
  }

  function randomLabels(n) {
    const codes = shuffled([...Array(LETTERS.length * DIGITS.length).keys()]).slice(0, n);
    return codes.map((c) => LETTERS[Math.floor(c / DIGITS.length)] + DIGITS[c % DIGITS.length]);
  }

  class RamureConsent {
    static info = {name: "ramure-consent", version: "1", parameters: {}, data: {consent: {type: 0}}};
    constructor(jsPsych) { this.jsPsych = jsPsych; }
    trial(display) {
      const agree = h("input", {type: "checkbox", id: "ramure-agree"});
      const go = h("button", {type: "button", id: "ramure-start", class: "jspsych-btn", disabled: true}, "Start");
      agree.addEventListener("change", () => { go.disabled = !agree.checked; });
      go.addEventListener("click", () => this.jsPsych.finishTrial({ramure: "consent", consent: true}));
      display.replaceChildren(h("div", {class: "ramure"},
        h("h1", {}, TASK.title),
        h("p", {class: "consent"}, TASK.consent),
        h("p", {}, agree, h("label", {for: "ramure-agree"}, " I have read this and agree to take part.")),
        h("p", {}, go)));
    }
  }

  class RamurePart {
    static info = {
      name: "ramure-part", version: "1",
      parameters: {set: {type: 2, default: 0}, part: {type: 2, default: 1}, parts: {type: 2, default: 1}},
      data: {groups: {type: 12}, shown: {type: 12}},
    };
    constructor(jsPsych) { this.jsPsych = jsPsych; }

    trial(display, trial) {
      const set = TASK.sets[trial.set];
      const start = performance.now();
      const order = shuffled(set.pictures);
      const labels = randomLabels(order.length);
      const label = Object.fromEntries(order.map((code, i) => [code, labels[i]]));
      const groups = [];          // lists of picture codes
      let selected = new Set();   // codes selected for a move
      let sortedMs = null;
      const answers = [];         // per group: {representative, usefulness, difference, representative_quality, words}
      const self = this;

      function picture(code) {
        const on = selected.has(code);
        return h("button", {type: "button", class: "ramure-pic" + (on ? " selected" : ""), "aria-pressed": on ? "true" : "false",
                            "data-code": code, "data-label": label[code],
                            onclick: () => { on ? selected.delete(code) : selected.add(code); sortPage(); }},
          h("img", {src: `img/${code}.png`, alt: `picture ${label[code]}`, width: TASK.size, height: TASK.size}),
          h("span", {}, label[code]));
      }
      function take() {
        const moving = order.filter((c) => selected.has(c));
        for (const g of groups) for (const c of moving) { const i = g.indexOf(c); if (i >= 0) g.splice(i, 1); }
        for (let i = groups.length - 1; i >= 0; i--) if (!groups[i].length) groups.splice(i, 1);
        selected = new Set();
        return moving;
      }
      function pool() { const placed = new Set(groups.flat()); return order.filter((c) => !placed.has(c)); }

      function sortPage() {
        const left = pool();
        const done = h("button", {type: "button", class: "jspsych-btn", id: "ramure-sorted", disabled: left.length > 0,
                                  onclick: () => { sortedMs = Math.round(performance.now() - start); groupPage(0); }}, "Next");
        display.replaceChildren(h("div", {class: "ramure"},
          h("p", {class: "ramure-progress"}, `Part ${trial.part} of ${trial.parts}`),
          h("p", {}, "Sort the pictures into groups of plants that look alike to you. Select pictures, then press " +
                     "\u201cNew group\u201d or \u201cMove here\u201d under a group."),
          h("div", {class: "ramure-pool", id: "ramure-pool"}, left.map(picture)),
          h("p", {}, h("button", {type: "button", class: "jspsych-btn", id: "ramure-new-group", disabled: selected.size === 0,
                                  onclick: () => { const m = take(); if (m.length) groups.push(m); sortPage(); }}, "New group"),
                     " ", h("button", {type: "button", class: "jspsych-btn", id: "ramure-unsort", disabled: selected.size === 0,
                                       onclick: () => { take(); sortPage(); }}, "Back to the pictures above")),
          groups.map((g, i) => h("fieldset", {class: "ramure-group", "data-group": i + 1},
            h("legend", {}, `Group ${i + 1}`),
            g.map(picture),
            h("button", {type: "button", class: "jspsych-btn ramure-move", disabled: selected.size === 0,
                         onclick: () => { const m = take(); const target = groups.indexOf(g); (target >= 0 ? groups[target] : groups[groups.push([]) - 1]).push(...m); sortPage(); }},
              "Move here"))),
          h("p", {}, done)));
      }

      function groupPage(k) {
        const g = groups[k];
        const a = answers[k] || (answers[k] = {representative: g.length === 1 ? g[0] : null, usefulness: null,
                                                 difference: null, representative_quality: null, words: []});
        const several = g.length > 1;
        const scale = (key, question) => h("fieldset", {class: "ramure-scale", "data-question": key},
          h("legend", {}, question),
          TASK.levels.map((level, i) => h("label", {},
            h("input", {type: "radio", name: `${key}-${k}`, value: i + 1, checked: a[key] === i + 1,
                        onchange: () => { a[key] = i + 1; check(); }}), " " + level, " ")));
        const words = h("input", {type: "text", id: "ramure-words", maxlength: 200, value: a.words.join(", "),
                                  oninput: () => { a.words = words.value.split(",").map((w) => w.trim()).filter(Boolean); check(); }});
        const next = h("button", {type: "button", class: "jspsych-btn", id: "ramure-next", onclick: () => {
          if (k + 1 < groups.length) groupPage(k + 1); else finish(); }}, k + 1 < groups.length ? "Next group" : "Finish this part");
        function check() {
          next.disabled = !(a.representative && a.usefulness && a.difference && (!several || a.representative_quality) && a.words.length);
        }
        display.replaceChildren(h("div", {class: "ramure"},
          h("p", {class: "ramure-progress"}, `Part ${trial.part} of ${trial.parts}: group ${k + 1} of ${groups.length}`),
          several ? h("p", {}, "Choose the picture that best stands for this group:") : null,
          h("div", {class: "ramure-group"}, g.map((code) => h("button", {
            type: "button", class: "ramure-pic" + (a.representative === code ? " selected" : ""), "data-code": code,
            "data-label": label[code], disabled: !several, "aria-pressed": a.representative === code ? "true" : "false",
            onclick: () => { a.representative = code; a.representative_quality = null; groupPage(k); }},
            h("img", {src: `img/${code}.png`, alt: `picture ${label[code]}`, width: TASK.size, height: TASK.size}),
            h("span", {}, label[code])))),
          scale("usefulness", TASK.questions.usefulness),
          scale("difference", TASK.questions.difference),
          several && a.representative ? scale("representative_quality", TASK.questions.representative_quality) : null,
          h("p", {}, h("label", {for: "ramure-words"}, "Words that describe this group (separate them with commas): "), words),
          h("p", {}, next)));
        check();
      }

      function finish() {
        const shown = order.map((code) => ({picture: code, label: label[code]}));
        const out = groups.map((g, k) => ({pictures: g.slice(), ...answers[k]}));
        self.jsPsych.finishTrial({ramure: "part", grammar: set.grammar, part: trial.part, parts: trial.parts,
                                  shown: shown, groups: out, sorted_ms: sortedMs, rt: Math.round(performance.now() - start)});
      }
      sortPage();
    }
  }

  function thanks(display) {
    display.replaceChildren(h("div", {class: "ramure"},
      h("h1", {}, "Thank you"),
      h("p", {}, "All your answers are recorded. Your completion code: ", h("strong", {id: "ramure-code"}, TASK.completion_code))));
  }

  function externalId() {
    const params = new URLSearchParams(location.search);
    if (window.jatos && jatos.urlQueryParameters && jatos.urlQueryParameters.PROLIFIC_PID) return jatos.urlQueryParameters.PROLIFIC_PID;
    return params.get("PROLIFIC_PID") || params.get("participant") || null;
  }

  function save(jsPsych) {
    const data = jsPsych.data.get();
    if (window.jatos && jatos.submitResultData) return jatos.submitResultData(data.json()).then(() => jatos.endStudy && jatos.endStudy());
    if (typeof window.ramureSave === "function") return window.ramureSave(jsPsych);  // e.g. Pavlovia's plugin
    const link = h("p", {}, h("button", {type: "button", class: "jspsych-btn", id: "ramure-download",
                                          onclick: () => data.localSave("json", "ramure-results.json")}, "Download the answers"));
    jsPsych.getDisplayElement().append(link);
  }

  function run() {
    const run = Array.from(crypto.getRandomValues(new Uint8Array(8)), (b) => b.toString(16).padStart(2, "0")).join("");
    const jsPsych = initJsPsych({on_finish: () => { thanks(jsPsych.getDisplayElement()); return save(jsPsych); }});
    jsPsych.data.addProperties({ramure_study: TASK.study, ramure_run: run, external_id: externalId()});
    const sets = shuffled([...TASK.sets.keys()]);  // the order of the parts, random per participant
    const timeline = [{type: RamureConsent}];
    sets.forEach((set, i) => timeline.push({type: RamurePart, set: set, part: i + 1, parts: sets.length}));
    window.ramureJsPsych = jsPsych;
    return jsPsych.run(timeline);
  }

  window.RamureConsent = RamureConsent;
  window.RamurePart = RamurePart;
  if (window.jatos && jatos.onLoad) jatos.onLoad(run); else window.addEventListener("load", run);
})();
