//! The stretch of time a step, or a part of it, is taken over: made once per step from the
//! world's dt (checked where it is set, by [`check_dt`]) and handed to the method, which cuts it
//! into pieces for its stages.

use crate::error::Error;

/// A step's time: the whole step `dt`, moved over in `n` pieces of `h`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Span {
    /// The whole step.
    pub(crate) dt: f64,
    /// One piece: what a motion stage moves the critters over.
    pub(crate) h: f64,
    /// Pieces.
    pub(crate) n: u32,
}

impl Span {
    /// The whole step of `dt` (a dt [`check_dt`] let through), in one piece.
    pub(crate) fn of(dt: f64) -> Span {
        Span { dt, h: dt, n: 1 }
    }

    /// The whole step in `n` substeps of dt / n.
    pub(crate) fn split(self, n: u32) -> Span {
        self.over(self.dt, n)
    }

    /// `length` of this step (what is left of it, say) in `n` pieces of length / n.
    pub(crate) fn over(self, length: f64, n: u32) -> Span {
        Span {
            dt: self.dt,
            h: length / f64::from(n),
            n,
        }
    }
}

/// Checks a time step: a finite number greater than zero (the world's dt, whoever sets it).
pub fn check_dt(dt: f64) -> Result<(), Error> {
    if dt.is_finite() && dt > 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidWorld {
            field: "dt",
            value: dt.to_string(),
            reason: "must be finite and greater than zero".into(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_is_cut_into_equal_pieces() {
        let span = Span::of(0.5);
        assert_eq!(
            span.split(4),
            Span {
                dt: 0.5,
                h: 0.125,
                n: 4
            }
        );
        assert_eq!(span.over(0.3, 3).h, 0.3 / 3.0);
        assert_eq!(span.over(0.3, 3).dt, 0.5);
    }

    #[test]
    fn a_dt_that_is_not_a_positive_finite_number_is_refused() {
        for dt in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = check_dt(dt).expect_err("refused");
            assert!(e.to_string().contains("dt"), "{e}");
        }
    }
}
