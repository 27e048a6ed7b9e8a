(define (problem blocksworld-p06)
  (:domain blocksworld-4ops)
  (:objects
    b1 b2 b3 b4 b5
  )
  (:init
    (on-table b2)
    (on-table b5)
    (on b3 b5)
    (on b1 b3)
    (on b4 b1)
    (clear b2)
    (clear b4)
    (arm-empty)
  )
  (:goal (and
    (on b1 b4)
    (on b4 b3)
    (on b5 b2)
  ))
)
