"""The loop's machinery: the step that composes the parts (``closed_loop``), the law's and the
target's parts of it (``law``, ``target_step``), the records it reads and writes, an episode
made from the run's objects and run chunk by chunk (``episode``, ``stepper``), the same step
compiled (``compiled``, ``_kernel``, ``kernel_sources``), and the rows it logs (``timeseries``,
``checkpoint``)."""
