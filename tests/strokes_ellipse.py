"""Prints a stroke CSV (u,v,stroke) of one closed stroke: n points on an
ellipse in UV space, for the e2e tests' wounds on the hand.
usage: strokes_ellipse.py U V RU RV [N]"""
import math
import sys

u, v, ru, rv = (float(x) for x in sys.argv[1:5])
n = int(sys.argv[5]) if len(sys.argv) > 5 else 12
print("u,v,stroke")
for k in range(n):
    a = 2 * math.pi * k / n
    print("%.4f,%.4f,0" % (u + ru * math.cos(a), v + rv * math.sin(a)))
