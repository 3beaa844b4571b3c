"""skinsim from Python, notebook style: a wound closing and the colour of skin.

Run it from the source tree after `make build` (or anywhere after
`make install`, with the install's dist-packages folder on PYTHONPATH):

    PYTHONPATH=integrations/python python3 docs/examples/python_notebook.py [out.png]

Needs python3-numpy and python3-matplotlib (Debian packages). Each block
below is one notebook cell.
"""
import sys

import matplotlib

matplotlib.use("Agg")  # no display needed; drop this line in a notebook
import matplotlib.pyplot as plt
import numpy as np

import skinsim
from skinsim import heal, optics

print("skinsim", skinsim.version(), "from", skinsim.library_path)

# %% A healing run in memory: the default 30 x 30 x 4 mm block of skin with a
# 20 mm square wound, moist ("clean") healing, 21 days. Nothing is written:
# the run object is the same one `skinsim heal` uses, stepped from Python.
run = heal.Run(scenario="clean", days=21, area_every=0.25)
for day in (3, 7, 14, 21):
    run.advance_to(day)
    top = run.surface("epithelium")  # (ny, nx) top view, 0..1
    print("day %2d: %4.1f%% of the surface covered by epithelium" % (day, 100 * (top > 0.5).mean()))
curve = run.area()  # numpy arrays, one row per 0.25 days
closed = run.time_to_closure(0.05)
print("95%% closed after %.1f days" % closed if closed else "not closed within 21 days")

# %% A scab slows re-epithelialisation (seed 001 Fig. 4): the same wound, scab scenario.
scab = heal.Run(scenario="scab", days=21, area_every=0.25)
scab.advance_to(21)
curve_scab = scab.area()

# %% Reflectance spectra of three skins by Monte Carlo light transport
# (seed 003): melanin darkens the blue end, blood carves the haemoglobin
# bands at 540 and 575 nm.
skins = {"light (melanin 0.02)": dict(melanin=0.02, blood=0.02),
         "medium (melanin 0.12)": dict(melanin=0.12, blood=0.02),
         "dark (melanin 0.35)": dict(melanin=0.35, blood=0.02)}
spectra = {name: optics.spectrum(photons=20000, wl_step_nm=5, **p) for name, p in skins.items()}

# %% Plot both.
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
ax1.plot(curve["t_days"], curve["normalised_area"], label="clean (moist)")
ax1.plot(curve_scab["t_days"], curve_scab["normalised_area"], label="scab")
ax1.axhline(0.05, color="grey", ls=":", lw=1)
ax1.set_xlabel("days after injury")
ax1.set_ylabel("open wound area / initial area")
ax1.set_title("Wound closure (skinsim.heal)")
ax1.set_ylim(0, 1.05)
ax1.legend()
for name, s in spectra.items():
    rgb = optics.srgb_encode(s.colour())  # the skin's own colour for its line
    ax2.plot(s.wavelength_nm, s.reflectance, color=np.clip(rgb, 0, 1), lw=2.5, label=name)
    ax2.fill_between(s.wavelength_nm, s.reflectance - 2 * s.std_error,
                     s.reflectance + 2 * s.std_error, color="k", alpha=0.15, lw=0)
ax2.set_xlabel("wavelength (nm)")
ax2.set_ylabel("diffuse reflectance")
ax2.set_title("Skin reflectance (skinsim.optics)")
ax2.legend()
fig.tight_layout()
out = sys.argv[1] if len(sys.argv) > 1 else "skinsim_python_example.png"
fig.savefig(out, dpi=90)
print("wrote", out)
