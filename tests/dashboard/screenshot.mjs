// node tests/dashboard/screenshot.mjs URL OUT.png [WAIT_MS]: opens the dashboard in Debian's headless
// chromium (playwright-core, as the browser test), waits, and saves a screenshot of the page.
import { chromium } from 'playwright-core';

const [url, out, waitMs = '5000'] = process.argv.slice(2);
if (!url || !out) {
  console.error('usage: node screenshot.mjs URL OUT.png [WAIT_MS]');
  process.exit(2);
}
const browser = await chromium.launch({
  executablePath: '/usr/bin/chromium',
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
         '--disable-component-update', '--disable-sync'],
});
const page = await browser.newPage({ viewport: { width: 1600, height: 1000 } });
page.on('pageerror', (e) => console.error('page error:', e.message));
await page.goto(url);
await page.waitForTimeout(Number(waitMs));
// FPLOC_SELECT_ROBOT=r2: pick that robot in the fleet selector first (its nodes and readouts).
if (process.env.FPLOC_SELECT_ROBOT) {
  await page.selectOption('#robot', process.env.FPLOC_SELECT_ROBOT);
  await page.waitForTimeout(1500);
}
// FPLOC_SELECT_FLOOR=first: show that floor's plan (the floor selector; "" = the robot's floor).
if (process.env.FPLOC_SELECT_FLOOR !== undefined) {
  await page.selectOption('#floor', process.env.FPLOC_SELECT_FLOOR);
  await page.waitForTimeout(1500);
}
await page.screenshot({ path: out });
const state = await page.evaluate(() => ({ connected: window.__fploc?.connected, trail: window.__fploc?.trail?.length,
  floor: window.__fploc?.pose?.floor }));
console.error(`screenshot ${out}: ${JSON.stringify(state)}`);
await browser.close();
