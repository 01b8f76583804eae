import numpy as np
import pytest

from vtable.analytic import TwoDirectionalTable
from vtable.analytic.pitch import two_directional

control = pytest.importorskip("control")


def test_to_control_same_frequency_response():
    model = TwoDirectionalTable(two_directional(21.0))
    sys = model.to_control()
    f = np.geomspace(0.1, 50, 512)
    resp = control.frequency_response(sys, 2 * np.pi * f)
    ours = model.freqresp(f)  # (n_f, outputs, inputs)
    data = resp.frdata if hasattr(resp, "frdata") else resp.fresp
    np.testing.assert_allclose(np.moveaxis(np.asarray(data), -1, 0), ours, rtol=1e-10,
                               atol=1e-14)
    assert list(sys.output_labels) == list(model.outputs)
    np.testing.assert_allclose(np.sort_complex(control.poles(sys)),
                               np.sort_complex(model.poles()), rtol=1e-10)
