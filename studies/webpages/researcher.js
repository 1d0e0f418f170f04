"use strict";
// The researcher's page: live progress (polled every 3 s) and the CSV download, behind the token
// given after '#' in the address that `ramure study serve` printed.
const token = decodeURIComponent(location.hash.slice(1));
const summary = document.getElementById("summary");

async function get(path) {
  const r = await fetch(path, {headers: {Authorization: "Bearer " + token}});
  if (!r.ok) throw new Error((await r.json().catch(() => ({}))).error || r.statusText);
  return r;
}

function cell(row, text) {
  const td = document.createElement("td");
  td.textContent = text;
  row.appendChild(td);
}

async function refresh() {
  try {
    const p = await (await get("/api/researcher/progress")).json();
    document.getElementById("title").textContent = "Study progress: " + p.title;
    summary.textContent = `${p.participants.length} participants, ${p.finished} of ${p.tests} parts finished, ${p.answers} answers stored.`;
    const body = document.querySelector("#people tbody");
    body.replaceChildren();
    for (const person of p.participants) {
      const row = document.createElement("tr");
      row.dataset.code = person.code;
      cell(row, person.code);
      cell(row, person.consent ? "yes" : "withdrawn");
      cell(row, person.tests);
      cell(row, person.finished);
      cell(row, (person.elapsed_seconds / 60).toFixed(1));
      body.appendChild(row);
    }
  } catch (e) {
    summary.textContent = "Cannot read the progress: " + e.message;
  }
}

document.getElementById("download").addEventListener("click", async () => {
  try {
    const blob = await (await get("/api/researcher/export.zip")).blob();
    const a = document.createElement("a");
    a.href = URL.createObjectURL(blob);
    a.download = "study-csv.zip";
    a.click();
    URL.revokeObjectURL(a.href);
  } catch (e) {
    summary.textContent = "Download refused: " + e.message;
  }
});

refresh();
setInterval(refresh, 3000);
