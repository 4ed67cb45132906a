// Opens each HTML report in real headless Chromium (Debian's `chromium`,
// driven by puppeteer-core), and fails unless it loads with 0 console
// errors, 0 page errors and 0 failed requests, every picture decodes, and
// its screenshot is not blank. Saves the screenshots beside the pages
// (NAME.png) or into SCREENSHOT_DIR.
//
// Usage: node .ci/check_html.mjs PAGE.html...
import puppeteer from 'puppeteer-core';
import { inflateSync } from 'node:zlib';
import { readFileSync } from 'node:fs';
import { basename, dirname, join, resolve } from 'node:path';

const chromium = process.env.CHROMIUM || '/usr/bin/chromium';
const pages = process.argv.slice(2);
if (pages.length === 0) {
  console.error('no page to check');
  process.exit(1);
}

// Share of non-zero bytes in a PNG's filtered image data: a blank page
// (one colour) filters to almost all zeros.
function inkShare(png) {
  const idat = [];
  for (let at = 8; at < png.length; ) {
    const length = png.readUInt32BE(at);
    const type = png.toString('ascii', at + 4, at + 8);
    if (type === 'IDAT') idat.push(png.subarray(at + 8, at + 8 + length));
    at += 12 + length;
  }
  const data = inflateSync(Buffer.concat(idat));
  let ink = 0;
  for (const byte of data) if (byte !== 0) ink++;
  return ink / data.length;
}

const browser = await puppeteer.launch({
  executablePath: chromium,
  headless: true,
  args: ['--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage',
    '--disable-background-networking', '--disable-extensions', '--no-first-run',
    '--disable-component-update', '--disable-sync'],
});
let failed = 0;
for (const file of pages) {
  const page = await browser.newPage();
  await page.setViewport({ width: 1280, height: 900 });
  const errors = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(`console: ${m.text()}`); });
  page.on('pageerror', (e) => errors.push(`page error: ${e.message}`));
  page.on('requestfailed', (r) => errors.push(`request failed: ${r.url().slice(0, 80)}`));
  await page.goto('file://' + resolve(file), { waitUntil: 'load' });
  const facts = await page.evaluate(() => ({
    images: document.images.length,
    broken: [...document.images].filter((i) => !i.complete || i.naturalWidth === 0).length,
    svgs: document.querySelectorAll('svg').length,
    rows: document.querySelectorAll('tr').length,
    text: document.body.innerText.length,
  }));
  const shot = join(process.env.SCREENSHOT_DIR || dirname(file), basename(file, '.html') + '.png');
  await page.screenshot({ path: shot, fullPage: true });
  const ink = inkShare(readFileSync(shot));
  const blank = ink < 0.01 || facts.text < 100;
  console.log(`${file}: ${errors.length} console errors, ${facts.images} images (${facts.broken} broken), ` +
    `${facts.svgs} plots, ${facts.rows} table rows, ink ${(ink * 100).toFixed(1)} %; screenshot ${shot}`);
  for (const e of errors) console.log(`  ${e}`);
  if (errors.length > 0 || facts.broken > 0 || facts.images === 0 || blank) {
    console.log(`  FAILED: ${file}`);
    failed++;
  }
  await page.close();
}
await browser.close();
process.exit(failed ? 1 : 0);
