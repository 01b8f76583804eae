"""Interaction studies (report ch. 9): the five models side by side for one specimen and a
record (`interaction`), a yielding specimen played on the table and on a fixed base
(`yielding`), and a heights x records study scaled out on Dask (`scaleout`). The response
spectrum they use is a signal's (`vtable.signals.spectra`)."""
