"""Runs notebooks without Jupyter and stores their outputs in the .ipynb, so that GitHub shows the figures.

    python notebooks/execute.py notebooks/quickstart.ipynb [more.ipynb ...] [--small]

Why: the notebooks are saved with the outputs of a full-size run (printed tables, plots as PNG), and a
maintainer must be able to refresh them after a change to jaxnet on a machine without a Jupyter kernel
(jaxnet's test environment has none). Each notebook's code cells run in order in one namespace, as a kernel
would run them, and as ``tests/test_notebooks.py`` runs them (which checks the numbers in small mode).
Per code cell the notebook gets what the inline backend would show: stdout and stderr as stream outputs,
the value of a last bare expression (``text/plain``, not for a cell ending in ``;``), and every matplotlib
figure open after the cell as a PNG (then closed). A cell that raises stops the run and leaves the file
unchanged.

``--small`` sets ``JAXNET_NOTEBOOK_SMALL=1`` (the notebooks' switch to small sizes, what the tests run);
without it the variable is set to ``0``: the full size, which is what the saved notebooks show. The time
of every cell is printed to the terminal (not stored).
"""

from __future__ import annotations

import argparse
import ast
import base64
import contextlib
import io
import json
import os
import pathlib
import sys
import time

#: resolution of the stored pictures (dots per inch): readable on GitHub, a few tens of kB per figure
DPI = 80


def _lines(text):
    """A notebook's multi-line string: a list of lines, each keeping its newline."""
    return text.splitlines(keepends=True)


def _run_cell(source, namespace, name):
    """Executes one cell's source in ``namespace``; returns its last bare expression's value or None."""
    tree = ast.parse(source, filename=name)
    last = None
    if tree.body and isinstance(tree.body[-1], ast.Expr) and not source.rstrip().endswith(";"):
        last = ast.Expression(tree.body.pop().value)
    exec(compile(tree, name, "exec"), namespace)  # noqa: S102
    if last is not None:
        return eval(compile(last, name, "eval"), namespace)  # noqa: S307
    return None


def _result_data(value):
    """The mime bundle a kernel stores for a cell's value: its repr, and for a value that shows itself as HTML
    (a plotly figure: the notebooks' 3D views) that HTML, with plotly's own JSON for JupyterLab's renderer. The
    HTML loads plotly.js from its CDN: a few tens of kB per view stored instead of 3.5 MB of script."""
    data = {"text/plain": _lines(repr(value))}
    to_json = getattr(value, "to_plotly_json", None)
    if to_json is not None:
        # a plotly figure's repr is its whole data: a line says what it is instead
        data["text/plain"] = [f"<plotly Figure with {len(value.data)} traces>"]
        data["text/html"] = _lines(value.to_html(include_plotlyjs="cdn", full_html=False))
        data["application/vnd.plotly.v1+json"] = json.loads(value.to_json())
    elif hasattr(value, "_repr_html_"):
        html = value._repr_html_()
        if html:
            data["text/html"] = _lines(html)
    return data


def _figure_outputs():
    """display_data outputs of every open matplotlib figure (PNG, base64), which are then closed."""
    import matplotlib.pyplot as plt

    outputs = []
    for number in plt.get_fignums():
        fig = plt.figure(number)
        png = io.BytesIO()
        fig.savefig(png, format="png", dpi=DPI, bbox_inches="tight")
        width, height = fig.get_size_inches() * fig.dpi
        outputs.append({"output_type": "display_data", "metadata": {},
                        "data": {"image/png": base64.b64encode(png.getvalue()).decode("ascii"),
                                 "text/plain": [f"<Figure size {width:.0f}x{height:.0f} with {len(fig.axes)} Axes>"]}})
    plt.close("all")
    return outputs


def execute(path, small=False):
    """Runs the notebook at ``path`` top to bottom and rewrites it with the outputs of every code cell.

    small: run with ``JAXNET_NOTEBOOK_SMALL=1`` (small sizes) instead of the full size. Returns the wall time (s).
    """
    import matplotlib

    matplotlib.use("Agg")
    path = pathlib.Path(path)
    notebook = json.loads(path.read_text())
    os.environ["JAXNET_NOTEBOOK_SMALL"] = "1" if small else "0"
    namespace = {"__name__": "__main__"}
    count, start = 0, time.perf_counter()
    for k, cell in enumerate(notebook["cells"]):
        if cell["cell_type"] != "code":
            continue
        count += 1
        out, err = io.StringIO(), io.StringIO()
        t0 = time.perf_counter()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            value = _run_cell("".join(cell["source"]), namespace, f"{path.name}[cell {k}]")
        print(f"{path.name} cell {k}: {time.perf_counter() - t0:.1f} s", file=sys.__stderr__, flush=True)
        outputs = [{"output_type": "stream", "name": name, "text": _lines(buf.getvalue())}
                   for name, buf in (("stdout", out), ("stderr", err)) if buf.getvalue()]
        if value is not None:
            outputs.append({"output_type": "execute_result", "execution_count": count, "metadata": {},
                            "data": _result_data(value)})
        outputs += _figure_outputs()  # the inline backend shows figures after the cell's value
        cell["execution_count"] = count
        cell["outputs"] = outputs
    # which size the saved outputs are of: the saved notebooks show the full size (tests/test_notebooks.py)
    notebook.setdefault("metadata", {})["jaxnet"] = {"size": "small" if small else "full"}
    path.write_text(json.dumps(notebook, indent=1, ensure_ascii=False) + "\n")
    return time.perf_counter() - start


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("notebooks", nargs="+", type=pathlib.Path)
    parser.add_argument("--small", action="store_true", help="small sizes (JAXNET_NOTEBOOK_SMALL=1), as the tests")
    args = parser.parse_args(argv)
    for path in args.notebooks:
        print(f"{path}: {execute(path, small=args.small):.0f} s", flush=True)


if __name__ == "__main__":
    main()
