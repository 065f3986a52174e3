#!/usr/bin/env python
"""The module layers as a picture: python tools/draw_layers.py [out=docs/figures/architecture_layers.png]

One band per layer of ``refpo_warp/utils/layering.py`` (top: cli), with its modules; an arrow from a band to a lower one
carries the number of imports between them, measured from the code (lazy imports included). No arrow goes up.
"""

import sys
from collections import Counter


def main(argv: list[str]) -> int:
    if any(a in ("-h", "--help") for a in argv):
        print(__doc__)
        return 0
    out = next((a.split("=", 1)[1] for a in argv if a.startswith("out=")), "docs/figures/architecture_layers.png")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from refpo_warp.utils.atomic_files import atomic_write
    from refpo_warp.utils.layering import LAYERS, first_party_modules, import_graph, layer_of, upward_imports

    graph = import_graph(first_party_modules())
    edges = Counter((layer_of(m), layer_of(t)) for m, ts in graph.items() for t in ts
                    if layer_of(m) and layer_of(t) and layer_of(m) != layer_of(t))  # fmt: skip
    names = {layer: sorted({(m.split(".")[1] if m.startswith("refpo_warp.") else "tasks/<family>/" + m.split(".")[-1])
                            for m in graph if layer_of(m) == layer and m.count(".") <= 2})  # fmt: skip
             for layer in LAYERS}
    names["core"] = [n for n in names["core"] if not n.startswith("tasks/")] + ["tasks/<family>/ (env code)"]
    names["app"] = [n for n in names["app"] if not n.startswith("tasks/")] + ["tasks/<family>/{bench,report}"]
    layers = list(LAYERS)
    fig, ax = plt.subplots(figsize=(11, 7.5))
    height, gap = 1.0, 0.55
    y = {layer: (len(layers) - 1 - i) * (height + gap) for i, layer in enumerate(layers)}
    for layer in layers:
        ax.add_patch(plt.Rectangle((0, y[layer]), 9.6, height, facecolor="#e8eef7", edgecolor="#345"))
        ax.text(0.12, y[layer] + height / 2, layer, fontsize=13, weight="bold", va="center")
        text = ", ".join(names[layer])
        lines, line = [], ""
        for word in text.split(" "):
            if len(line) + len(word) > 76:
                lines.append(line)
                line = ""
            line += word + " "
        lines.append(line)
        ax.text(1.05, y[layer] + height / 2, "\n".join(lines), fontsize=8.5, va="center", family="monospace")
    for k, ((a, b), count) in enumerate(sorted(edges.items(), key=lambda e: (layers.index(e[0][0]), e[0][1]))):
        x = 9.9 + 0.42 * k
        ax.annotate("", xy=(x, y[b] + height), xytext=(x, y[a]), arrowprops={"arrowstyle": "->", "color": "#345"})
        ax.text(x + 0.04, (y[a] + y[b] + height) / 2, str(count), fontsize=7.5, rotation=90, va="center")
    ax.set_xlim(-0.1, 10.0 + 0.42 * len(edges))
    ax.set_ylim(-0.2, y[layers[0]] + height + 0.2)
    ax.axis("off")
    upward = len(upward_imports(graph))
    ax.set_title(f"Module layers: imports only go down (arrows: import count between layers; upward: {upward})")
    with atomic_write(out) as f:
        fig.savefig(f, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
