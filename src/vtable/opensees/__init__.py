"""OpenSees specimens (`[specimen] kind = "opensees"`): any openseespy model on the virtual
table. `library` imports openseespy (an optional extra), `model` runs the user's file and
reads what vtable needs from the model it builds, `stepper` steps it with the platen."""
