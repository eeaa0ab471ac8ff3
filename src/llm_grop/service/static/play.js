// Progressive enhancement of the playground: the page works without this file.
// It fills the request box from the examples, shows that work is under way, and follows
// a run's server-sent events instead of reloading the page.
"use strict";
(function () {
  const form = document.getElementById("play");
  const box = document.getElementById("request");
  for (const link of document.querySelectorAll("a.example")) {
    link.addEventListener("click", (event) => {
      event.preventDefault();
      box.value = link.dataset.request;
      box.focus();
    });
  }
  if (form) {
    form.addEventListener("submit", (event) => {
      // The pressed button's name and value must still be sent: copy them first.
      const pressed = event.submitter;
      if (pressed && pressed.name) {
        const hidden = document.createElement("input");
        hidden.type = "hidden";
        hidden.name = pressed.name;
        hidden.value = pressed.value;
        form.appendChild(hidden);
      }
      for (const b of form.querySelectorAll("button")) b.disabled = true;
      document.getElementById("busy").hidden = false;
    });
  }
  const result = document.getElementById("result");
  if (result && !result.dataset.events &&
      (result.dataset.state === "queued" || result.dataset.state === "running")) {
    window.setTimeout(() => window.location.reload(), 1500);
  }
  if (result && result.dataset.events &&
      (result.dataset.state === "queued" || result.dataset.state === "running")) {
    const list = document.getElementById("events");
    const status = document.getElementById("status");
    const source = new EventSource(result.dataset.events);
    source.addEventListener("progress", (event) => {
      const item = document.createElement("li");
      item.textContent = JSON.parse(event.data).message;
      list.appendChild(item);
      status.textContent = "running…";
    });
    source.addEventListener("end", () => {
      source.close();
      window.location.reload();
    });
  }
})();
