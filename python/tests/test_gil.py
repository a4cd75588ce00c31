"""The GIL is released while the library works: another Python thread runs during a decode."""
import threading
import time

import isowave


def test_a_python_thread_runs_while_decode_works(large_isw):
    # The first call imports NumPy's C API, Python code that hands the GIL over by itself: not measured.
    isowave.decode(large_isw, percent=1)
    stamps, stop = [], threading.Event()

    def ticker():
        while not stop.is_set():
            stamps.append(time.perf_counter())
            time.sleep(0.001)

    thread = threading.Thread(target=ticker)
    thread.start()
    try:
        while not stamps:
            time.sleep(0.001)
        # Held during the call, the GIL would stop the ticker for all of it; the middle half of the call
        # excludes the hand-overs at its ends (the switch interval is 5 ms).
        for _ in range(5):
            start = time.perf_counter()
            isowave.decode(large_isw, limit=True)
            end = time.perf_counter()
            quarter = (end - start) / 4
            inside = [t for t in stamps if start + quarter < t < end - quarter]
            if quarter > 0.01 and inside:
                break
        assert quarter > 0.01, f"the decode took only {4 * quarter:.3f} s: too short to tell"
        assert inside, "no tick of the other thread in the middle half of the decode"
    finally:
        stop.set()
        thread.join()
