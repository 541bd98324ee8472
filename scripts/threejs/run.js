const { chromium } = require('playwright-core');
(async () => {
  const browser = await chromium.launch({ executablePath: '/usr/bin/chromium', args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'] });
  for (const f of process.argv.slice(2)) {
    const page = await browser.newPage();
    page.on('console', m => console.error('console:', m.text()));
    page.on('pageerror', e => console.error('pageerror:', e.message));
    // PAGE: load.html (one GLB) or tiles.html (a tileset.json).
    await page.goto(`http://127.0.0.1:8765/${process.env.PAGE || 'load.html'}?f=${f}`);
    await page.waitForFunction(() => window.result, null, { timeout: 300000, polling: 200 });
    console.log(JSON.stringify(await page.evaluate(() => window.result)));
    await page.close();
  }
  await browser.close();
})().catch(e => { console.error(e); process.exit(1); });
