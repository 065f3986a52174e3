#!/usr/bin/env python
"""The layers as a picture: python docs/figures/draw_layers.py [out=docs/figures/architecture_layers.png]

One band per layer of ``refpo_warp/utils/layering.py`` (top: cli), with its folders and their module counts; an arrow
from a band to a lower one carries the number of imports between them, measured from the code (lazy imports
included). No arrow goes up.
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

    from refpo_warp.utils.atomic_files import save_figure
    from refpo_warp.utils.layering import LAYERS, first_party_modules, import_graph, layer_of, upward_imports

    graph = import_graph(first_party_modules())
    edges = Counter(
        (layer_of(m), layer_of(t))
        for m, ts in graph.items()
        for t in ts
        if layer_of(m) and layer_of(t) and layer_of(m) != layer_of(t)
    )
    counts = Counter(m.split(".")[1] for m in graph if layer_of(m))
    shown: dict[str, str] = {}
    layers = list(LAYERS)
    width = 14.6  # the bands: the app layer's folders in one line
    fig, ax = plt.subplots(figsize=(15.5, 5.6))
    height, gap = 0.8, 0.45
    y = {layer: (len(layers) - 1 - i) * (height + gap) for i, layer in enumerate(layers)}
    for layer in layers:
        ax.add_patch(plt.Rectangle((0, y[layer]), width, height, facecolor="#e8eef7", edgecolor="#345"))
        ax.text(0.12, y[layer] + height / 2, layer, fontsize=13, weight="bold", va="center")
        text = "   ".join(f"{shown.get(f, f + '/')} {counts[f]}" for f in LAYERS[layer])
        ax.text(1.3, y[layer] + height / 2, text, fontsize=9.5, va="center", family="monospace")
    for k, ((a, b), count) in enumerate(sorted(edges.items(), key=lambda e: (layers.index(e[0][0]), e[0][1]))):
        x = width + 0.3 + 0.42 * k
        ax.annotate("", xy=(x, y[b] + height), xytext=(x, y[a]), arrowprops={"arrowstyle": "->", "color": "#345"})
        ax.text(x + 0.04, (y[a] + y[b] + height) / 2, str(count), fontsize=7.5, rotation=90, va="center")
    ax.set_xlim(-0.1, width + 0.4 + 0.42 * len(edges))
    ax.set_ylim(-0.2, y[layers[0]] + height + 0.2)
    ax.axis("off")
    upward = len(upward_imports(graph))
    ax.set_title(
        "Layers of refpo_warp (folder/ and its module count; tasks/ installs as refpo_warp.tasks); "
        f"arrows: imports between layers, downward only (upward: {upward})",
        fontsize=10,
    )
    save_figure(fig, out, dpi=110, bbox_inches="tight")
    plt.close(fig)
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
