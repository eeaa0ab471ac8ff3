// Rates with one key (1-5) or click through the JSON API, then shows the next picture
// without reloading. Without JavaScript the form posts and the page reloads instead.
(() => {
  const form = document.getElementById("rate-form");
  if (!form) return;
  const csrf = document.querySelector('meta[name="csrf-token"]').content;
  const picture = document.getElementById("picture");
  const buttons = form.querySelectorAll("button[name=rating]");
  const status = document.getElementById("status");
  let busy = false;

  const hold = (on) => { busy = on; buttons.forEach((b) => { b.disabled = on; }); };
  const say = (text) => { status.textContent = text; status.hidden = !text; };
  // A rating only counts for a picture the rater has seen: wait until it has loaded.
  picture.addEventListener("load", () => hold(false));
  picture.addEventListener("error", () => { hold(false); say("The picture did not load; reload the page."); });

  function show(next) {
    form.dataset.item = next.item;
    document.getElementById("item").value = next.item;
    document.getElementById("objects").textContent = next.objects.join(", ");
    document.getElementById("progress").textContent = `${next.done + 1} / ${next.total}`;
    picture.src = next.image;
  }

  async function rate(rating) {
    if (busy) return;
    hold(true);
    say("");
    try {
      const sent = await fetch("/api/ratings", {
        method: "POST", credentials: "same-origin",
        headers: { "Content-Type": "application/json", "X-CSRF-Token": csrf },
        body: JSON.stringify({ item: form.dataset.item, rating }),
      });
      if (sent.status === 401) { window.location.assign("/"); return; }
      if (!sent.ok && sent.status !== 409) {
        say((await sent.json()).error); hold(false); return;
      }
      const next = await (await fetch("/api/next", { credentials: "same-origin" })).json();
      if (next.item === null) { window.location.assign("/rate"); return; }
      show(next);
    } catch (err) {
      say("Could not reach the server; press the rating again.");
      hold(false);
    }
  }

  form.addEventListener("submit", (ev) => {
    ev.preventDefault();
    if (ev.submitter) rate(Number(ev.submitter.value));
  });
  document.addEventListener("keydown", (ev) => {
    if (ev.altKey || ev.ctrlKey || ev.metaKey || ev.repeat) return;
    if (/^[1-5]$/.test(ev.key)) { ev.preventDefault(); rate(Number(ev.key)); }
  });
  if (!picture.complete) hold(true);
})();
