"""What people read: a run's report (markdown, HTML, figures, the task page), Table 1
exports, and comparisons of runs (comparison.py computes them from run folders,
comparison_page.py writes them). The top room of eval: it may import every other one but
serving.
"""
