// page.js URL DRAWING.svg SCREENSHOT.png — drives the page at / in headless Chromium
// (playwright-core): loads a drawing, asks for numbers, presses Compute, waits for the picture,
// prints the status line and the number of face paths drawn, and takes a screenshot.
const { chromium } = require('playwright-core');
(async () => {
  const browser = await chromium.launch({ executablePath: '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync'] });
  const page = await browser.newPage({ viewport: { width: 1100, height: 1300 } });
  await page.goto(process.argv[2]);
  await page.setInputFiles('#file', process.argv[3]);
  await page.waitForFunction(() => document.getElementById('req').value.includes('"kind":"svg"'));
  await page.check('#num');
  await page.click('#go');
  await page.waitForSelector('#pic svg', { timeout: 20000 });
  console.log('status:', await page.textContent('#st'));
  console.log('face paths:', await page.locator('#pic svg g#faces path').count());
  await page.screenshot({ path: process.argv[4], fullPage: false });
  await browser.close();
})().catch(e => { console.error(e); process.exit(1); });
