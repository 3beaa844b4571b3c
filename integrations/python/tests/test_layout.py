"""The ctypes mirrors of the C structs (skinsim/_lib.py) have the sizes and
field offsets the C compiler gives them (abi_layout.c, compiled and run by
tests/e2e_python.sh, which passes its output in SKINSIM_ABI_LAYOUT)."""
import ctypes
import os
import unittest

from skinsim import _lib as L


class Layout(unittest.TestCase):
    def test_structs_match_the_headers(self):
        path = os.environ.get("SKINSIM_ABI_LAYOUT")
        if not path:
            self.skipTest("SKINSIM_ABI_LAYOUT not set (run through tests/e2e_python.sh)")
        checked = 0
        with open(path) as f:
            for line in f:
                parts = line.split()
                if parts[0] == "struct":
                    cls = getattr(L, parts[1])
                    self.assertEqual(ctypes.sizeof(cls), int(parts[2]), "sizeof " + parts[1])
                else:
                    cls = getattr(L, parts[1])
                    self.assertEqual(getattr(cls, parts[2]).offset, int(parts[3]),
                                     "offsetof %s.%s" % (parts[1], parts[2]))
                checked += 1
        self.assertGreater(checked, 50)


if __name__ == "__main__":
    unittest.main()
