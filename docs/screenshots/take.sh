#!/usr/bin/env bash
# Screenshots of the shipped blind reference report and of a three-run comparison, as a reader
# sees them: headless Chromium (Debian: apt-get install chromium) at 1280 px wide.
# Rebuild the pages first (robofollow report docs/results/blind; robofollow report
# docs/results/baselines/scene2-{text,blind,form} --out docs/results/comparisons/scene2-text-blind-form).
set -euo pipefail
cd "$(dirname "$0")/../.."
shot() {  # name, page, height in px
    chromium --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size="1280,$3" \
        --screenshot="docs/screenshots/$1.png" "file://$PWD/$2" 2>/dev/null
}
shot blind-report docs/results/blind/report.html 3000
shot three-runs docs/results/comparisons/scene2-text-blind-form/comparison.html 1600
