// Floors of a building: GET /api/floors lists them; the map shows the plan of the pose's floor
// (pose_t.floor) unless the viewer picks another one in the floor selector ("robot's floor" follows
// the pose again). A single plan is one floor: the selector stays hidden.
export class FloorView {
  constructor(select, onPlan) {
    this.select = select;
    this.onPlan = onPlan;    // (plan, floorName) => void
    this.floors = [];
    this.shown = null;       // the floor whose plan the map shows
    this.robotFloor = null;  // the pose's floor
    this.loading = null;
    select.addEventListener('change', () => this.update(true));
  }
  // After /api/plan was loaded (the initial floor).
  async load(initialShown) {
    const r = await fetch('/api/floors', { cache: 'no-store' });
    const j = r.ok ? await r.json() : { floors: [], initial: null };
    this.floors = j.floors || [];
    this.shown = initialShown !== undefined ? initialShown : j.initial;
    const auto = document.createElement('option');
    auto.value = '';
    auto.textContent = "robot's floor";
    this.select.replaceChildren(auto, ...this.floors.map((f) => {
      const o = document.createElement('option');
      o.value = f.name;
      o.textContent = `${f.name} (${f.elevation >= 0 ? '+' : ''}${Number(f.elevation).toFixed(2)} m)`;
      return o;
    }));
    this.select.value = '';
    this.select.parentElement.classList.toggle('hidden', this.floors.length < 2);
    this.update(false);
  }
  // The pose's floor (pose_t.floor; "" or missing = unknown).
  setRobotFloor(name) {
    if (!name || name === this.robotFloor) return;
    this.robotFloor = name;
    this.update(false);
  }
  wanted() { return this.select.value || this.robotFloor || this.shown; }
  async update(byViewer) {
    const want = this.wanted();
    if (!want || want === this.shown || this.floors.length < 2) return;
    if (!this.floors.some((f) => f.name === want)) return;
    this.loading = want;
    try {
      const r = await fetch(`/api/plan?floor=${encodeURIComponent(want)}`, { cache: 'no-store' });
      if (!r.ok || this.loading !== want) return;
      const plan = await r.json();
      this.shown = want;
      this.onPlan(plan, want, byViewer);
    } catch (e) { console.warn('floor plan load failed', e); }
  }
  // For the readouts: "first" or "ground (map shows first)"; "single floor" for a plain plan.
  describe(poseFloor) {
    if (!poseFloor) return '–';
    if (this.floors.length < 2) return 'single floor';  // a plain plan (its one floor is named 0)
    return poseFloor + (this.shown && this.floors.length > 1 && this.shown !== poseFloor ? ` (map shows '${this.shown}')` : '');
  }
}
